"""``python -m pinflex``: the ``pinflex`` command."""

import sys

from pinflex.cli import main

sys.exit(main())
