"""dwr-gym's training, evaluation and reporting, and the ``dwr-gym`` command line (:mod:`train.cli`)."""
