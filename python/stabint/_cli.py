"""The ``stabint-run`` console command that pip installs (pyproject.toml, ``[project.scripts]``):
the C++ tool ``stabint-run`` itself (tools/run), compiled into the extension, with the same
options, output and exit status (``stabint-run --help``)."""

import sys
from typing import List, Optional

from . import _stabint


def main(argv: Optional[List[str]] = None) -> int:
    """Runs stabint-run with ``argv`` (default: this process's arguments, without the program's
    name) and returns its exit status."""
    args = sys.argv[1:] if argv is None else list(argv)
    # The tool writes to the process's file descriptors, past Python's buffers: empty those first
    # so that what was printed before comes first.
    sys.stdout.flush()
    sys.stderr.flush()
    return _stabint._run_cli(["stabint-run"] + [str(a) for a in args])


if __name__ == "__main__":
    sys.exit(main())
