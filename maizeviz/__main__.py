import sys

from maizeviz.cli import main

sys.exit(main())
