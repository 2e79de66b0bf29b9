"""Shared fixtures for the policy plugins: tiny features, batches, a LeRobotDataset, CLI runs."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch
from lerobot.configs.types import FeatureType, PolicyFeature

import lerobot_env_rmb  # noqa: F401 - registers --policy.type=mlp/sarnn, as LeRobot's discovery

STATE_DIM = ACTION_DIM = 7
IMAGE = (3, 32, 32)
FPS = 31
FRONT = "observation.images.front"
EPISODES, EPISODE_LEN = 2, 24


@pytest.fixture(autouse=True)
def one_torch_thread():
    """One intra-op thread: the suite runs on 2 shared cores with ``-n 2`` workers."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


@pytest.fixture
def features() -> tuple[dict, dict]:
    """(input_features, output_features) of one 32x32 camera and UR5e-sized state/action."""
    inputs = {
        "observation.state": PolicyFeature(FeatureType.STATE, (STATE_DIM,)),
        FRONT: PolicyFeature(FeatureType.VISUAL, IMAGE),
    }
    return inputs, {"action": PolicyFeature(FeatureType.ACTION, (ACTION_DIM,))}


def synthetic_episode(length: int, phase: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Smooth joint trajectories, actions leading the state, and a square that follows joint 0.

    The image depends on the state, so both policies can learn something from either input.
    """
    t = np.arange(length)[:, None] / FPS
    freqs = np.linspace(0.5, 1.5, STATE_DIM)[None]
    state = np.sin(2 * np.pi * freqs * t + phase).astype(np.float32)
    action = np.sin(2 * np.pi * freqs * (t + 1 / FPS) + phase).astype(np.float32)
    images = np.zeros((length, IMAGE[1], IMAGE[2], 3), dtype=np.uint8)
    for i, s in enumerate(state):
        x = int((s[0] + 1) / 2 * (IMAGE[2] - 8))
        y = int((s[1] + 1) / 2 * (IMAGE[1] - 8))
        images[i, y : y + 8, x : x + 8] = (255, 160, 40)
    return state, action, images


def to_policy_batch(state, action, images, length: int) -> dict[str, torch.Tensor]:
    """Windows of ``length`` + 1 frames (as LeRobot's delta indices give), batched over starts."""
    starts = range(0, len(state) - length)
    obs = slice(0, length + 1)
    return {
        "observation.state": torch.stack([torch.from_numpy(state[s:][obs]) for s in starts]),
        FRONT: torch.stack(
            [torch.from_numpy(images[s:][obs]).permute(0, 3, 1, 2).float() / 255 for s in starts]
        ),
        "action": torch.stack([torch.from_numpy(action[s + 1 : s + 1 + length]) for s in starts]),
        "action_is_pad": torch.zeros(len(starts), length, dtype=torch.bool),
    }


@pytest.fixture
def observation():
    """``observation(batch, seed)``: a random state + front-camera observation batch."""

    def _observation(batch: int, seed: int = 0) -> dict[str, torch.Tensor]:
        g = torch.Generator().manual_seed(seed)
        return {
            "observation.state": torch.randn(batch, STATE_DIM, generator=g),
            FRONT: torch.rand(batch, *IMAGE, generator=g),
        }

    return _observation


@pytest.fixture
def windows():
    """``windows(length, phase)``: every window of one synthetic episode, as a policy batch."""

    def _windows(length: int, phase: float = 0.0) -> dict[str, torch.Tensor]:
        return to_policy_batch(*synthetic_episode(EPISODE_LEN, phase), length)

    return _windows


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory) -> Path:
    """A 2-episode LeRobotDataset v3 (state, one 32x32 video camera, action) at 31 fps."""
    from lerobot.datasets import LeRobotDataset

    root = tmp_path_factory.mktemp("dataset") / "tiny"
    dataset = LeRobotDataset.create(
        repo_id="local/tiny",
        fps=FPS,
        root=root,
        robot_type="ur5e",
        features={
            "observation.state": {"dtype": "float32", "shape": (STATE_DIM,), "names": None},
            FRONT: {
                "dtype": "video",
                "shape": (IMAGE[1], IMAGE[2], 3),
                "names": ["height", "width", "channels"],
            },
            "action": {"dtype": "float32", "shape": (ACTION_DIM,), "names": None},
        },
    )
    for episode in range(EPISODES):
        state, action, images = synthetic_episode(EPISODE_LEN, phase=episode)
        for s, a, img in zip(state, action, images, strict=True):
            dataset.add_frame(
                {"observation.state": s, "action": a, FRONT: img, "task": "Insert the peg."}
            )
        dataset.save_episode()
    dataset.finalize()
    return root


@pytest.fixture
def train_and_eval(tiny_dataset, train_and_eval_on):
    """``lerobot-train`` a few steps on the tiny dataset, then ``lerobot-eval`` the checkpoint
    on Insert's 32x32 front camera; returns the eval info."""

    def _run(policy_type: str, policy_args: list[str]) -> dict:
        result = train_and_eval_on(tiny_dataset, policy_type, policy_args, TINY_ENV_ARGS)
        assert result["config"]["type"] == policy_type
        return result["eval"]

    return _run


TINY_ENV_ARGS = ["--env.cameras=[front]", "--env.image_width=32", "--env.image_height=32"]


# ------------------------------------------------------------- expert data with depth (DP3)
DEPTH_SIZE = 32  # square images of the expert dataset and of the env it is evaluated on
DEPTH_WORLDS = (1, 4)  # episode i is world DEPTH_WORLDS[i], reset with seed i (rmb-collect)


@pytest.fixture(scope="session")
def expert_depth_dataset(shared_expert_dataset) -> Path:
    """Two Insert demonstrations by the scripted expert (front camera, RGB + depth), converted
    as ``rmb-convert to-lerobot --depth`` does: depth is ``observation.images.front_depth``.
    Built once per run (DP3 and Flow Policy tests, any xdist worker); read-only."""
    return shared_expert_dataset("insert", world_idx=DEPTH_WORLDS, size=DEPTH_SIZE, depth=True)


@pytest.fixture
def train_and_eval_on(tmp_path, lerobot_cli):
    """``lerobot-train`` a few steps on ``dataset``, then ``lerobot-eval`` it on ``env_type``
    (default Insert) with extra ``env_args`` (e.g. ``--env.depth=true``); returns the
    checkpoint's config and the eval info (``{"config": ..., "eval": ...}``)."""

    def _run(
        dataset: Path,
        policy_type: str,
        policy_args: list[str],
        env_args: list[str],
        env_type: str = "rmb_ur5e_insert",
    ) -> dict:
        out = tmp_path / "train"
        train = lerobot_cli(
            "lerobot_train",
            [
                f"--policy.type={policy_type}",
                *policy_args,
                "--policy.device=cpu",
                "--policy.push_to_hub=false",
                f"--dataset.repo_id=local/{dataset.name}",
                f"--dataset.root={dataset}",
                f"--output_dir={out}",
                "--steps=3",
                "--batch_size=2",
                "--num_workers=0",
                "--save_freq=3",
                "--log_freq=1",
                "--wandb.enable=false",
            ],
            tmp_path,
        )
        assert train.returncode == 0, train.stderr[-3000:]
        checkpoint = out / "checkpoints" / "last" / "pretrained_model"
        evaluation = lerobot_cli(
            "lerobot_eval",
            [
                f"--policy.path={checkpoint}",
                "--policy.device=cpu",
                f"--env.type={env_type}",
                *env_args,
                "--env.episode_length=5",
                "--eval.n_episodes=1",
                "--eval.batch_size=1",
                f"--output_dir={tmp_path / 'eval'}",
            ],
            tmp_path,
        )
        assert evaluation.returncode == 0, evaluation.stderr[-3000:]
        return {
            "config": json.loads((checkpoint / "config.json").read_text()),
            "eval": json.loads((tmp_path / "eval" / "eval_info.json").read_text()),
        }

    return _run


# ------------------------------------------------------ save/load of a policy with EMA weights
@pytest.fixture
def fit_batch():
    """``fit_batch(policy, batch, steps)``: AdamW (lr 3e-3) on one batch, seeded, in train mode;
    ``policy.update()`` after each step for policies with an EMA (what lerobot-train calls)."""

    def _fit(policy, batch: dict, steps: int = 100, update: bool = False) -> None:
        optimizer = torch.optim.AdamW(policy.get_optim_params(), lr=3e-3)
        policy.train()
        torch.manual_seed(0)
        for _ in range(steps):
            loss, _ = policy.forward(batch)
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            if update:
                policy.update()

    return _fit


@pytest.fixture
def ema_save_load(tmp_path):
    """``ema_save_load(policy, batch, obs) -> (loaded, expected, got)``: train ``policy`` 3
    steps on ``batch()``, updating its EMA copy after each (so the averaged weights used for
    inference differ from the trained ones), save it with its processors, load both back with
    ``from_pretrained``; return the loaded policy and the original's and the loaded policy's
    actions for ``obs`` under the same noise."""
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.policies.factory import get_policy_class, make_pre_post_processors

    def run(policy, batch, obs: dict) -> tuple:
        policy.train()
        optimizer = torch.optim.AdamW(policy.get_optim_params(), lr=1e-2)
        for _ in range(3):
            loss, _ = policy.forward(batch())
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            policy.update()
        state_dim = policy.config.input_features["observation.state"].shape[0]
        action_dim = policy.config.output_features["action"].shape[0]
        stats = {
            "observation.state": {"min": -torch.ones(state_dim), "max": torch.ones(state_dim)},
            "action": {"min": torch.zeros(action_dim), "max": torch.full((action_dim,), 2.0)},
        }
        pre, post = make_pre_post_processors(policy.config, dataset_stats=stats)
        for part in (policy, pre, post):
            part.save_pretrained(tmp_path)

        config = PreTrainedConfig.from_pretrained(tmp_path)
        loaded = get_policy_class(config.type).from_pretrained(tmp_path)
        pre2, post2 = make_pre_post_processors(config, pretrained_path=str(tmp_path))
        noise = torch.randn(1, config.horizon, action_dim)
        policy.reset()
        loaded.reset()
        expected = post(policy.select_action(pre(obs), noise=noise))
        return loaded, expected, post2(loaded.select_action(pre2(obs), noise=noise))

    return run


# ------------------------------------------------------ depth scenes for point-cloud policies
class DepthBoxScene:
    """32x32 depth images (mm) of a table at 0.8 m with an 8x8-pixel box at 0.6 m whose place
    depends on the seed, a wall at 3 m above; and training windows whose actions follow the
    box (learnable from the point cloud alone). For DP3 and the policies built on it."""

    size = 32
    depth_key = "observation.images.front_depth"
    state_dim = action_dim = 7

    def depth_mm(self, batch_shape: tuple[int, ...], seed: int = 0) -> torch.Tensor:
        size = self.size
        g = torch.Generator().manual_seed(seed)
        depth = torch.full((*batch_shape, 1, size, size), 800.0)
        depth[..., : size // 4, :] = 3000.0
        row, col = (int(v) for v in torch.randint(size // 4, size - 8, (2,), generator=g))
        depth[..., row : row + 8, col : col + 8] = 600.0
        return depth

    def observation(self, batch: int, seed: int = 0) -> dict[str, torch.Tensor]:
        g = torch.Generator().manual_seed(seed)
        return {
            "observation.state": torch.randn(batch, self.state_dim, generator=g),
            self.depth_key: self.depth_mm((batch,), seed),
        }

    def windows(self, batch: int, policy) -> dict[str, torch.Tensor]:
        cfg = policy.config
        depth = torch.cat([self.depth_mm((1, cfg.n_obs_steps), seed=i) for i in range(batch)])
        box = (depth[:, -1, 0] < 700).nonzero()[:, 1:].float().view(batch, -1, 2).mean(1)
        action = (box / self.size).repeat(1, 4)[:, : self.action_dim, None].transpose(1, 2)
        return {
            "observation.state": torch.zeros(batch, cfg.n_obs_steps, self.state_dim),
            self.depth_key: depth,
            "action": 2 * action.repeat(1, cfg.horizon, 1) - 1,
            "action_is_pad": torch.zeros(batch, cfg.horizon, dtype=torch.bool),
        }


@pytest.fixture
def depth_box() -> DepthBoxScene:
    """The box scene (:class:`DepthBoxScene`): ``depth_box.observation(2)``,
    ``depth_box.windows(8, policy)``, ``depth_box.depth_mm((2, 3))``."""
    return DepthBoxScene()


# ------------------------------------------------------ sampling policies: seeded action chunks
@pytest.fixture
def assert_seeded_chunks():
    """``assert_seeded_chunks(policy, obs, n_actions)``: for a policy that samples its chunk
    from noise (``predict_action_chunk(obs, noise=...)``): the same seed gives the same chunk
    of ``n_actions`` actions, another seed another one (noise is its only randomness), and
    ``select_action`` executes the chunk of a given noise step by step."""

    def check(policy, obs: dict, n_actions: int) -> None:
        def chunk(seed: int) -> torch.Tensor:
            policy.reset()
            torch.manual_seed(seed)
            return policy.predict_action_chunk(obs)

        first = chunk(3)
        batch, action_dim = first.shape[0], first.shape[-1]
        assert first.shape == (batch, n_actions, action_dim) and torch.isfinite(first).all()
        torch.testing.assert_close(chunk(3), first)
        assert not torch.allclose(chunk(4), first)

        noise = torch.randn(batch, policy.config.horizon, action_dim)
        policy.reset()
        expected = policy.predict_action_chunk(obs, noise=noise)
        policy.reset()
        actions = [policy.select_action(obs, noise=noise) for _ in range(n_actions)]
        torch.testing.assert_close(torch.stack(actions, dim=1), expected)

    return check
