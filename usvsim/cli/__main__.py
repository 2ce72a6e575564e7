"""``python -m usvsim.cli``: the ``usvsim`` command."""

import sys

from usvsim.cli.main import main

sys.exit(main())
