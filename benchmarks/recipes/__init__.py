"""The recipes: the trainings behind the shipped agents and the docs' tables, each a shell script run as it is (hours
on 2 cores), with a module of the same name that names it in the suite."""
