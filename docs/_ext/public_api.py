"""The public API's objects have pages of their own under the names users import
(``transient.simulate``, docs/api.rst); the pages of the modules that define them leave them out,
so that each is described once and a reference to it has one target."""
from __future__ import annotations

import transient

#: The names ``from transient import …`` gives a user (``errors`` is a module of its own page).
PUBLIC = tuple(n for n in transient.__all__ if n not in ("errors", "__version__"))


def _defined_publicly(obj) -> bool:
    return any(obj is getattr(transient, name) for name in PUBLIC)


def skip_public_on_module_pages(app, what, name, obj, skip, options):
    if what == "module" and _defined_publicly(obj):
        return True
    return None


def setup(app):
    app.connect("autodoc-skip-member", skip_public_on_module_pages)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
