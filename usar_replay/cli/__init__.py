"""cli: the ``usar`` command: arguments, progress, exit codes, one-line errors.

The face of the package: it may import every layer; nothing imports it.

Where things are (one job per name):

- ``main``: the entry point; parses, runs the command, turns errors into exit codes.
- ``parser``: builds the ``usar`` argument parser from every command's ``add_parser``.
- ``parser_parts``: what the commands build their sub-parsers from (the parser class whose bad
  command line is one ``usar: error:`` line, argument types, shared option groups).
- ``options``: reads parsed arguments into the layers' values (the world, the settings, the
  mission's limits, the thresholds, the outputs), checked before any work; the world's
  options (`add_world_options`) live there too, beside the code that reads them.
- ``commands/<command>``: one module per command (``usar record`` is ``commands/record.py``).
- ``exits``, ``textout``, ``window``: exit codes, lines that fit 100 columns, the time window
  of ``usar echo`` and ``usar log``.
"""
