"""``python -m pysindy_xl.cli``: the ``pysindy-xl`` command."""

import sys

from . import main

sys.exit(main())
