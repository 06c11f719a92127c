"""``python -m lgt_bridge.cli`` (what the ``lgt-bridge`` command runs)."""
import sys

from . import main

sys.exit(main())
