"""What every benchmark does the same way: timing against a reference in the same run (:mod:`.timing`), the record
of the machine and the JSON written (:mod:`.record`), the docs blocks rendered from that JSON (:mod:`.docs`), and
the commands and recipes run as a user runs them (:mod:`.commands`)."""
