"""The ``usar`` command's entry point: parse, run the command, turn errors into exit codes.

User errors (:class:`usar_replay.core.errors.UsarError`) are printed as one line, ``usar: error:
...``, without a traceback; anything else is a bug and raises. Everything printed on stdout, and
every error, goes through :mod:`usar_replay.core.safe_text`: a log's strings are anyone's. The
exit codes are in :mod:`usar_replay.cli.exits`; each command lives in its own module of this
package.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from usar_replay.cli.exits import EXIT_INTERRUPTED, EXIT_OK
from usar_replay.cli.parser import build_parser
from usar_replay.core.errors import UsarError

__all__ = ["main"]


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``usar`` console script; returns the process exit code."""
    from usar_replay.core import signals
    from usar_replay.core.safe_text import safe, safe_stdout

    try:
        with signals.handled(), safe_stdout():
            try:
                parser = build_parser()
                args = parser.parse_args(argv)
                code: int = args.func(args)
            except UsarError as err:
                # its text may quote a log's (a topic's name, a definition's type): shown, not
                # obeyed
                print(f"usar: error: {safe(str(err))}", file=sys.stderr)
                return err.exit_code
            except BrokenPipeError:
                return EXIT_OK
    except KeyboardInterrupt as err:
        # here too when it came while the handlers were being set (a Ctrl-C at start-up)
        # a plain Ctrl-C is "interrupted"; SIGTERM/SIGHUP say which signal ended the command
        code = signals.exit_code(err)
        text = str(err) if code != EXIT_INTERRUPTED else "interrupted"
        print(f"usar: {text}", file=sys.stderr)
        return code
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
