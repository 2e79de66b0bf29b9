"""Packaging: one import namespace, every sub-package shipped, plugin name LeRobot finds."""

import importlib
import importlib.metadata
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
SETUPTOOLS = PYPROJECT["tool"]["setuptools"]


def import_name(directory: Path) -> str:
    """The import name a source directory installs as, through the package-dir mapping."""
    rel = directory.relative_to(ROOT).as_posix()
    for name, source in sorted(SETUPTOOLS["package-dir"].items(), key=lambda kv: -len(kv[1])):
        if source not in ("", ".") and (rel == source or rel.startswith(source + "/")):
            return ".".join([name, *rel.removeprefix(source).strip("/").split("/")]).strip(".")
    return rel.replace("/", ".")


def test_every_source_package_is_listed_for_the_wheel():
    sources = ["rmb_lerobot", "envs", "converters", "policies_extra"]
    found = {
        import_name(init.parent)
        for source in sources
        for init in (ROOT / source).rglob("__init__.py")
        if "__pycache__" not in init.parts
    }
    missing = found - set(SETUPTOOLS["packages"])
    assert not missing, f"add to [tool.setuptools] packages in pyproject.toml: {sorted(missing)}"


def test_distribution_name_is_discoverable_by_lerobot():
    assert PYPROJECT["project"]["name"].startswith("lerobot_env_")
    assert importlib.metadata.metadata("lerobot_env_rmb")["Name"] == "lerobot_env_rmb"


def test_no_generic_top_level_modules_are_installed(tmp_path):
    # Outside the repository only the rmb_lerobot namespace (and the plugin module) exist.
    code = (
        "import importlib.util as u; "
        "assert u.find_spec('rmb_lerobot.envs') and u.find_spec('rmb_lerobot.converters'); "
        "assert not any(u.find_spec(m) for m in ('envs', 'converters', 'policies_extra'))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr


def test_console_scripts_point_at_real_functions():
    for name, target in PYPROJECT["project"]["scripts"].items():
        module, _, func = target.partition(":")
        assert callable(getattr(importlib.import_module(module), func)), name


def test_lazy_public_names_resolve():
    import rmb_lerobot

    assert sorted(rmb_lerobot.__all__) == sorted(rmb_lerobot._LAZY)
    for name in rmb_lerobot.__all__:
        assert getattr(rmb_lerobot, name) is not None
