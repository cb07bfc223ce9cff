"""The command line (``rockbench ...``): :mod:`.main` (the parser and the run, compare,
report, info, scenes and engines commands), :mod:`.common` (what every command shares: option
types, the one ``--setting ENGINE.KEY=VALUE`` grammar, scene and motion input, JSON and file
output), and one module per group of commands (:mod:`.choosing`, :mod:`.maps`,
:mod:`.fragility`).

The entry point is :func:`rockbench.cli.main.main` (``python -m rockbench`` and the
``rockbench`` script); this package imports nothing on import.
"""
