import sys

from activevision.cli import main

sys.exit(main())
