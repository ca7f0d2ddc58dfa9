"""The ``usar`` commands, one module each, named for its command (``usar record`` is
:mod:`usar_replay.cli.commands.record`).

Why a folder of their own: a command is named like the layer it drives (``usar log``, ``usar
echo``, ``usar info``, ``usar recover`` beside the ``log`` layer's ``echo``, ``info`` and
``recover``); kept here, a command module never sits beside, or shadows, a layer. Each module
has ``add_parser(sub)`` (its options, cheap to import) and ``run(args)`` (its work, importing
the layers it needs lazily).
"""
