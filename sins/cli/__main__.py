"""``python -m sins.cli``: the ``sins`` command."""

import sys

from sins.cli import main

sys.exit(main())
