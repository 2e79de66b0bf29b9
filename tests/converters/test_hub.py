"""--push-to-hub: everything up to the upload calls, with the Hub replaced by a recorder."""

from __future__ import annotations

import huggingface_hub
import pytest

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.cli.convert import main
from rmb_lerobot.converters import ConvertOptions, push_dataset, to_lerobot


class FakeHub:
    """Records the HfApi calls LeRobotDataset.push_to_hub makes (and the dataset card)."""

    def __init__(self, monkeypatch):
        self.calls: list[tuple[str, dict]] = []
        for name in ("create_repo", "create_branch", "upload_folder", "delete_tag", "create_tag"):
            monkeypatch.setattr(huggingface_hub.HfApi, name, self._recorder(name))
        monkeypatch.setattr(huggingface_hub.RepoCard, "push_to_hub", self._card_recorder())

    def _recorder(self, name):
        def record(api, *args, **kwargs):
            self.calls.append((name, {"args": args, **kwargs}))

        return record

    def _card_recorder(self):
        def push(card, repo_id, **kwargs):
            self.calls.append(("card", {"repo_id": repo_id, "text": str(card), **kwargs}))

        return push

    def call(self, name: str) -> dict:
        found = [kwargs for called, kwargs in self.calls if called == name]
        assert len(found) == 1, (name, self.calls)
        return found[0]


def test_push_sends_the_whole_converted_dataset(demos, tmp_path, monkeypatch, no_network):
    hub = FakeHub(monkeypatch)
    repo_id, root = to_lerobot(
        [demos],
        repo_id="someone/rmb_insert",
        output=tmp_path / "ds",
        options=ConvertOptions(camera_names=("hand",)),
        video_codec="h264",
        progress=False,
    )
    push_dataset(repo_id, root, private=True, branch="v1", tags=["sim"])
    assert [name for name, _ in hub.calls] == [
        "create_repo",
        "create_branch",
        "upload_folder",
        "card",
        "delete_tag",
        "create_tag",
    ]
    repo = hub.call("create_repo")
    assert repo["repo_id"] == "someone/rmb_insert" and repo["repo_type"] == "dataset"
    assert repo["private"] is True
    upload = hub.call("upload_folder")
    assert upload["folder_path"] == root and upload["revision"] == "v1"
    assert upload["repo_type"] == "dataset" and "images/" in upload["ignore_patterns"]
    uploaded = {p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()}
    assert {N.RMB_METADATA_PATH, N.GR00T_MODALITY_PATH, "meta/info.json"} <= uploaded
    assert any(p.startswith("videos/observation.images.hand/") for p in uploaded)
    card = hub.call("card")
    assert card["revision"] == "v1" and "RoboManipBaselines" in card["text"]
    assert "sim" in card["text"] and '"fps": 31.25' in card["text"]


def test_cli_pushes_after_converting(demos, tmp_path, monkeypatch, no_network, capsys):
    hub = FakeHub(monkeypatch)
    code = main(
        [
            "to-lerobot",
            str(demos),
            "--repo-id",
            "someone/insert",
            "--output",
            str(tmp_path / "ds"),
            "--camera-names",
            "front",
            "--video-codec",
            "h264",
            "--push-to-hub",
        ]
    )
    assert code == 0, capsys.readouterr().err
    assert hub.call("upload_folder")["folder_path"] == tmp_path / "ds"
    assert hub.call("create_repo")["private"] is False
    assert "pushed to https://huggingface.co/datasets/someone/insert" in capsys.readouterr().out


def test_push_needs_a_hub_repo_id_before_any_work(demos, tmp_path, capsys):
    code = main(["to-lerobot", str(demos), "--output", str(tmp_path / "ds"), "--push-to-hub"])
    assert code == 2 and "--repo-id NAMESPACE/NAME" in capsys.readouterr().err
    assert not (tmp_path / "ds").exists()


@pytest.mark.parametrize("repo_id", ["noslash", "a/b/c", "/x"])
def test_repo_id_shape_is_checked(repo_id):
    from rmb_lerobot.converters.hub import check_repo_id

    with pytest.raises(ValueError, match="NAMESPACE/NAME"):
        check_repo_id(repo_id)
