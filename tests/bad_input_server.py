"""Child side of ``test_bad_input_fuzz.py``: a fork server that imports LeRobot once.

Reads one JSON request per line on stdin (``{"episode": ..., "dest": ...}``). For each, it
forks a child (this process runs no threads, so forking is safe) that does what a user does
with an episode, and answers one JSON line: the child's outcome, or how it died. A child that
does not answer within ``timeout`` seconds is killed and reported as a hang.
"""

from __future__ import annotations

import json
import os
import select
import signal
import sys
import time
import traceback

import numpy as np

from rmb_lerobot import open_episode
from rmb_lerobot.converters import ConvertOptions, to_lerobot
from rmb_lerobot.errors import RmbFormatError


def exercise(episode: str, dest: str) -> dict:
    """Open, read every key, then convert: the whole user path, in the child."""
    try:
        with open_episode(episode) as ep:
            ep.validate()
            _ = ep.fps, dict(ep.attrs)
            for key in ep:
                np.asarray(ep[key][:])
        to_lerobot(
            [episode],
            output=dest,
            options=ConvertOptions(depth=True),
            video_codec="h264",
            progress=False,
        )
        return {"outcome": "accepted", "message": ""}
    except RmbFormatError as exc:
        return {"outcome": "rejected", "message": str(exc)}
    except BaseException as exc:
        message = "".join(traceback.format_exception(exc))
        return {"outcome": f"foreign {type(exc).__name__}", "message": message}


def _read_all(fd: int, pid: int, timeout: float) -> bytes | None:
    chunks, deadline = [], time.monotonic() + timeout
    while (left := deadline - time.monotonic()) > 0:
        ready, _, _ = select.select([fd], [], [], left)
        if not ready:
            break
        chunk = os.read(fd, 1 << 16)
        if not chunk:
            return b"".join(chunks)
        chunks.append(chunk)
    os.kill(pid, signal.SIGKILL)
    return None


def serve(timeout: float) -> None:
    for line in sys.stdin:
        request = json.loads(line)
        read_end, write_end = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: keep the protocol's stdout clean, answer through the pipe
            os.close(read_end)
            os.dup2(2, 1)
            result = exercise(request["episode"], request["dest"])
            os.write(write_end, json.dumps(result).encode())
            os._exit(0)
        os.close(write_end)
        payload = _read_all(read_end, pid, timeout)
        os.close(read_end)
        _, status = os.waitpid(pid, 0)
        if payload is None:
            answer = {"outcome": "hang", "message": f"no answer within {timeout} s"}
        elif not payload or os.waitstatus_to_exitcode(status) != 0:
            code = os.waitstatus_to_exitcode(status)
            answer = {"outcome": f"crash (exit code {code})", "message": payload.decode()}
        else:
            answer = json.loads(payload)
        print(json.dumps(answer), flush=True)


if __name__ == "__main__":
    serve(float(sys.argv[1]) if len(sys.argv) > 1 else 60.0)
