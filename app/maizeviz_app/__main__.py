import sys

from maizeviz_app.main import run

sys.exit(run())
