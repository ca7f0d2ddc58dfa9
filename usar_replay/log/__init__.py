"""log: one run as an MCAP file.

The file's structure and CRCs (``mcapfile``), writing and reading messages (``bag``), the opened
run every command shares (``run``), and the two commands that only look at a file: ``info`` and
``recover``. The only place that imports ``mcap``. It may import ``core`` and ``world``.
"""
