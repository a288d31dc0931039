"""``python -m fabricate`` is the ``fabricate`` command."""
import sys

try:
    from .app.cli import main

    code = main()
except KeyboardInterrupt:  # Ctrl-C while the command line itself was still loading
    print("interrupted", file=sys.stderr)
    code = 130
sys.exit(code)
