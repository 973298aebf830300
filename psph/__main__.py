import sys

from psph.cli import main

sys.exit(main())
