"""cli: the ``usar`` command: arguments, progress, exit codes, one-line errors.

The face of the package: it may import every layer; nothing imports it.
"""
