"""Progress bars for episodes and frames (tqdm), fed directly or from worker processes."""

from __future__ import annotations

from typing import Protocol

from tqdm import tqdm


class Progress(Protocol):
    def frames(self, count: int) -> None: ...

    def episode_done(self) -> None: ...


class Bars:
    """Two tqdm bars: episodes converted, frames converted."""

    def __init__(self, episodes: int, frames: int, enabled: bool = True):
        self._episodes = tqdm(total=episodes, desc="episodes", unit="ep", disable=not enabled)
        self._frames = tqdm(
            total=frames, desc="frames", unit="frame", disable=not enabled, position=1
        )

    def frames(self, count: int) -> None:
        self._frames.update(count)

    def episode_done(self) -> None:
        self._episodes.update(1)

    def close(self) -> None:
        self._frames.close()
        self._episodes.close()

    def __enter__(self) -> Bars:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class QueueProgress:
    """Progress reported by a worker process through a multiprocessing queue."""

    def __init__(self, events):
        self._events = events

    def frames(self, count: int) -> None:
        self._events.put(("frames", count))

    def episode_done(self) -> None:
        self._events.put(("episode", 1))


def forward(event: tuple[str, int], progress: Progress) -> None:
    """Apply an event a :class:`QueueProgress` sent."""
    kind, count = event
    if kind == "frames":
        progress.frames(count)
    else:
        progress.episode_done()
