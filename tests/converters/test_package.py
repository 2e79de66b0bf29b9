"""``rmb_lerobot.converters``: its lazy names stay the functions, whatever was imported first.

A fresh ``rmb-convert`` process that imports the implementing modules before the functions is
part of ``tests/cli/test_convert.py`` (the killed conversions run that way).
"""

from __future__ import annotations

import importlib.util
import pkgutil

import rmb_lerobot.converters as converters


def test_no_lazy_name_is_also_a_submodule():
    """Importing a submodule sets the package attribute of its name, hiding a lazy function."""
    submodules = {m.name for m in pkgutil.iter_modules(converters.__path__)}
    assert submodules, "package not found"
    assert not submodules & set(converters.__all__)
    for name in converters.__all__:
        assert importlib.util.find_spec(f"rmb_lerobot.converters.{name}") is None, name
