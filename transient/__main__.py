"""``python -m transient`` is the ``transient`` command."""
from .cli import entry

entry()
