"""RMB's real envs from a YAML like RMB's ``envs/configs/Real*DemoEnv.yaml``.

The YAML holds ``robot_ip`` (dual: ``robot_ip_left``, ``robot_ip_right``), ``camera_ids``
(camera name -> RealSense serial) and, added here, ``driver: sim | sdk`` (``sim``: a dry run on
the MuJoCo twins, on loopback). Any other key is an option of
:class:`~rmb_lerobot.envs.real.options.RealOptions` or of the env core; RMB's sensor keys this
package does not drive yet (``gelsight_ids``, ...) are warned about and ignored.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from rmb_lerobot.envs.real.options import RealOptions

if TYPE_CHECKING:
    from rmb_lerobot.envs.base import RmbEnv


def load_real_config(path: str | Path) -> dict[str, Any]:
    """Read a real-env YAML.

    Args:
        path: The YAML file.

    Returns:
        Its keys and values.

    Raises:
        ValueError: The file does not hold a mapping.
    """
    data = yaml.safe_load(Path(path).read_text())
    if data is None:
        return {}
    if not isinstance(data, Mapping):
        raise ValueError(f"{path}: a real-env config must be a mapping, got {type(data).__name__}")
    return dict(data)


def make_real_env(
    env: str, config: str | Path | Mapping[str, Any] | None = None, **kwargs: Any
) -> RmbEnv:
    """One of RMB's real envs, configured like RMB's.

    Args:
        env: ``RealUR5eDemo``, ``RealXarm7Demo``, ``RealUR5eDualDemo`` (or any alias:
            ``RealUR5eDemoEnv``, ``real_ur5e_demo``).
        config: A YAML path or its contents (``robot_ip``, ``camera_ids``, ``driver``, ...).
        **kwargs: Override or add options (:class:`RealOptions` fields and the env core's:
            ``action_mode``, ``cameras``, ``depth``, ...).

    Returns:
        The env (connected; ``close()`` it).

    Raises:
        ValueError: ``env`` is not a real env, or a bad option.
    """
    from rmb_lerobot.envs.registry import entry_for

    entry = entry_for(env)
    if entry.simulator != "real":
        raise ValueError(f"{env!r} is not a real env (it is {entry.rmb_env_name})")
    given = load_real_config(config) if isinstance(config, str | Path) else dict(config or {})
    options = {**given, **kwargs}
    names = {f.name for f in fields(RealOptions)}
    real = RealOptions(**{k: v for k, v in options.items() if k in names})
    configs = real.camera_configs_for(entry.robot_record)
    if "render_mode" not in options and "render_camera" not in options:
        if configs:
            options["render_camera"] = "front" if "front" in configs else next(iter(configs))
        else:
            options["render_mode"] = None
    options.setdefault("depth", any(getattr(c, "use_depth", False) for c in configs.values()))
    return entry.make(**options)
