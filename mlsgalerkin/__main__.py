"""``python -m mlsgalerkin ...``: the command line (see :mod:`mlsgalerkin.cli`)."""

import sys

from mlsgalerkin.cli import main

if __name__ == "__main__":
    sys.exit(main())
