"""``python -m hydroarm``: the command line (`hydroarm.cli.main`)."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
