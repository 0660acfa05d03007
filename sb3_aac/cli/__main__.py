"""``python -m sb3_aac.cli``: the ``sb3-aac`` command."""

import sys

from sb3_aac.cli import main

sys.exit(main())
