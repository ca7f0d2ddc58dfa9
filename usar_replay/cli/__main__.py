"""``python -m usar_replay.cli``: the ``usar`` command."""

import sys

from usar_replay.cli.main import main

sys.exit(main())
