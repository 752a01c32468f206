"""``python -m placement.cli``: the ``anchorplan`` command."""

import sys

from placement.cli import main

sys.exit(main())
