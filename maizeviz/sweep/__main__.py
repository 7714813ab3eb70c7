"""``python -m maizeviz.sweep SPEC --out DIR``: the ``maizeviz sweep`` command."""

import sys

from maizeviz.sweep.command import main

sys.exit(main())
