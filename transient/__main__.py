"""``python -m transient`` is the ``transient`` command."""
import sys

from .cli import main

sys.exit(main())
