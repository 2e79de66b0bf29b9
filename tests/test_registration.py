"""LeRobot discovers this package with no flags, and registration is one mechanism."""

import subprocess
import sys
import textwrap

from rmb_lerobot import registration


def run_python(code: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_plugin_module_imports_in_a_fresh_interpreter(tmp_path):
    result = run_python(
        "import lerobot_env_rmb; print(lerobot_env_rmb.REGISTERED_MODULES)", tmp_path
    )
    assert result.returncode == 0, result.stderr


def test_lerobots_own_plugin_discovery_imports_us(tmp_path):
    # What lerobot-train/lerobot-eval do at start-up: import every lerobot_env_* distribution.
    result = run_python(
        """
        import sys
        from lerobot.utils.import_utils import register_third_party_plugins
        register_third_party_plugins()
        assert "lerobot_env_rmb" in sys.modules, sorted(m for m in sys.modules if "rmb" in m)
        """,
        tmp_path,
    )
    assert result.returncode == 0, result.stderr


def test_register_all_makes_env_types_known_to_lerobot(tmp_path, monkeypatch):
    module = tmp_path / "rmb_test_env_config.py"
    module.write_text(
        textwrap.dedent(
            """
            from dataclasses import dataclass
            from lerobot.envs.configs import EnvConfig

            @EnvConfig.register_subclass("rmb_registration_probe")
            @dataclass
            class ProbeEnv(EnvConfig):
                @property
                def gym_kwargs(self):
                    return {}
            """
        )
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    imported = registration.register_all(
        env_modules=("rmb_test_env_config",),
        policy_modules=(),
        device_modules=(),
        optimizer_modules=(),
    )
    assert imported == ["rmb_test_env_config"]
    assert "rmb_registration_probe" in registration.registered_env_types()


def test_a_broken_registration_module_fails_loudly():
    # LeRobot only logs plugin import errors; our own call must raise so tests catch it.
    try:
        registration.register_all(env_modules=("rmb_lerobot.does_not_exist",), policy_modules=())
    except ModuleNotFoundError as exc:
        assert "does_not_exist" in str(exc)
    else:  # pragma: no cover
        raise AssertionError("expected ModuleNotFoundError")
