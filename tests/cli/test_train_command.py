"""vla.train_command: the printed lerobot-train line survives a paste into bash (issue 30)."""

from __future__ import annotations

import json
import shlex
import subprocess

from rmb_lerobot.policies_extra import vla


def _dataset(root, cameras=("front", "hand")):
    features = {
        f"observation.images.{camera}": {"dtype": "video", "shape": [32, 32, 3], "info": {}}
        for camera in cameras
    }
    (root / "meta").mkdir(parents=True)
    (root / "meta" / "info.json").write_text(json.dumps({"features": features}))
    return root


def test_the_printed_command_is_the_argument_list_once_bash_splits_it(tmp_path, capsys):
    root = _dataset(tmp_path / "my data")  # a space in the path too
    args = vla.train_args(root, "pi0")
    assert any(a.startswith("--rename_map={") for a in args)

    line = vla.train_command(root, "pi0")
    assert shlex.split(line) == ["lerobot-train", *args]
    echoed = subprocess.run(
        ["bash", "-c", f'set -- {line}; printf "%s\\n" "$@"'],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.splitlines()
    assert echoed == ["lerobot-train", *args]
    rename = next(a for a in echoed if a.startswith("--rename_map="))
    assert json.loads(rename.removeprefix("--rename_map=")) == vla.camera_rename_map(
        ["front", "hand"], "pi0"
    )

    assert vla.main([str(root), "pi0"]) == 0
    assert capsys.readouterr().out.strip() == line
