"""The rollout side shared by policies that read a window of past observations and execute a
chunk of predicted actions (DP3, Flow Policy, ManiFlow).

LeRobot calls ``select_action`` with one observation per step; such a policy keeps the last
``n_obs_steps`` observations of each input it reads and a queue of ``n_action_steps`` actions,
and predicts a new chunk only when the queue is empty. A policy mixes
:class:`ObservationHistory` in before ``PreTrainedPolicy`` and defines which inputs it reads
(:attr:`observation_keys`) and how a window becomes a chunk (:meth:`sample_chunk`).
"""

from __future__ import annotations

from collections import deque

import torch
from lerobot.policies.utils import populate_queues
from lerobot.utils.constants import ACTION, OBS_STATE
from torch import Tensor, nn


class ObservationHistory:
    """Observation history and action queue for ``select_action``/``predict_action_chunk``."""

    name: str
    # Appended to the error for missing inputs: where they come from.
    missing_input_hint = "RMB env types deliver depth with --env.depth=true"

    @property
    def observation_keys(self) -> tuple[str, ...]:
        """The observation inputs the policy reads (state first)."""
        raise NotImplementedError

    def sample_chunk(self, window: dict[str, Tensor], noise: Tensor | None) -> Tensor:
        """(B, n_action_steps, A) actions for observation windows (B, n_obs_steps, ...)."""
        raise NotImplementedError

    def get_optim_params(self) -> list[nn.Parameter]:
        return [p for p in self.parameters() if p.requires_grad]

    def reset(self) -> None:
        """Start an episode: forget the observation history and the queued actions."""
        self._queues = {key: deque(maxlen=self.config.n_obs_steps) for key in self.observation_keys}
        self._queues[ACTION] = deque(maxlen=self.config.n_action_steps)

    def _check_inputs(self, batch: dict[str, Tensor]) -> None:
        missing = [k for k in self.observation_keys if k not in batch]
        if missing:
            raise KeyError(f"{self.name} needs {missing}: {self.missing_input_hint}")

    def _window_from_history(self, batch: dict[str, Tensor]) -> dict[str, Tensor]:
        """Append one observation (B, ...) to the history; the last ``n_obs_steps`` frames."""
        self._check_inputs(batch)
        self._queues = populate_queues(self._queues, {k: batch[k] for k in self.observation_keys})
        return {k: torch.stack(list(self._queues[k]), dim=1) for k in self.observation_keys}

    @torch.no_grad()
    def predict_action_chunk(self, batch: dict[str, Tensor], noise: Tensor | None = None) -> Tensor:
        """(B, n_action_steps, A) actions from the current step on.

        ``batch`` is either one observation (B, ...), appended to the history kept since
        :meth:`reset`, or a window (B, n_obs_steps, ...) as the dataset gives.
        """
        self.eval()
        if batch[OBS_STATE].ndim == 2:
            batch = self._window_from_history(batch)
        return self.sample_chunk(batch, noise)

    @torch.no_grad()
    def select_action(self, batch: dict[str, Tensor], noise: Tensor | None = None) -> Tensor:
        """Next action (B, A): a new chunk every ``n_action_steps`` calls, queued in between."""
        window = self._window_from_history(batch)
        if not self._queues[ACTION]:
            self.eval()
            self._queues[ACTION].extend(self.sample_chunk(window, noise).transpose(0, 1))
        return self._queues[ACTION].popleft()

    def as_windows(self, batch: dict[str, Tensor]) -> dict[str, Tensor]:
        """A training batch with a time axis on every observation (``n_obs_steps == 1``
        batches come without one)."""
        if batch[OBS_STATE].ndim == 2:
            return {**batch, **{k: batch[k].unsqueeze(1) for k in self.observation_keys}}
        return batch
