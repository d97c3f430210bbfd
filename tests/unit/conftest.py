"""Fixtures of the unit tests."""
from __future__ import annotations

import importlib.util
import sys

import numba
import pytest


@pytest.fixture
def kern(tmp_path, monkeypatch):
    """A module ``kern`` defining ``double(x)`` (not yet compiled), imported from a file in
    ``tmp_path``, with numba's cache folder there too: a function whose cache files a test may
    make, read and lose."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "numba"))
    source = tmp_path / "kern.py"
    source.write_text("def double(x):\n    return 2 * x\n")
    spec = importlib.util.spec_from_file_location("kern", source)
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "kern", module)
    spec.loader.exec_module(module)
    return module
