"""``python -m fabricate`` is the ``fabricate`` command."""
import sys

from .cli import main

sys.exit(main())
