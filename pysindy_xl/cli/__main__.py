"""``python -m pysindy_xl.cli``: the ``pysindy-xl`` command."""

import sys

from .commands import main

sys.exit(main())
