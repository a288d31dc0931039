"""The ``fabricate`` command's old place (``fabricate.app.cli`` now): console scripts installed before
the application layer moved into ``fabricate.app`` still call ``fabricate.cli:main``."""
from fabricate.app.cli import main

__all__ = ["main"]
