"""``python -m activevision``: the ``activevision`` command (for an environment whose scripts
folder is not on ``PATH``)."""

import sys

from activevision.cli import main

if __name__ == "__main__":
    sys.exit(main())
