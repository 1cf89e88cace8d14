"""One module per ``dwr-gym`` command: each adds its parser (``add_parser``) and runs it (``run``), parsing and
checking the arguments and calling into :mod:`train.learning`, :mod:`train.evaluation` and :mod:`train.reporting`.
The helpers they share are in :mod:`train.commands.shared`, which imports no command."""
