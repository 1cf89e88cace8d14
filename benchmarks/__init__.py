"""The benchmarks of dwr-gym, one suite: ``python -m benchmarks list`` names each with one line, and
``python -m benchmarks run NAME [ARGS] [--docs]`` runs one (``--docs``: it writes its JSON under docs/ and the blocks
of the docs it produces are rendered from that JSON). ``python -m benchmarks render`` renders every generated block
of the README and the docs from the JSON already written.

Each benchmark is one module in the package of what it measures (speed/, training/, learning/, robustness/,
quality/, testing/, datasets/) with a ``main(argv)`` and, if it writes docs, ``BLOCKS``; each recipe is a shell script
in recipes/; ``registry.py`` names them. What they share (timing against a reference in the same run, the record of the machine, the JSON, the
docs blocks, running commands as a user) lives in ``core/``. The suite sits on top: it imports ``train``,
``baselines`` and ``dwr_gym``; nothing imports it.
"""
