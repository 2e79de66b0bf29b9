"""The rollout server over real local sockets (Unix and TCP), with the doubles of conftest."""

from __future__ import annotations

import json
import os
import signal
import socket
import stat
import threading
import time

import pytest

from rmb_lerobot.rollout import Address, RolloutClient, RolloutError, RolloutServer, stop_on_signals

# Two of the instructions the PushEnv double knows (conftest): with "banana" the stub pushes.
BANANA, APPLE = "Put the banana in the blue basket.", "Put the apple in the black basket."


def test_instruction_reaches_policy_and_env_and_the_episode_reports_success(
    make_push_env, policy, serving, sock_path
):
    env = make_push_env(max_steps=20, goal=3.0)
    with serving(env, policy, f"unix:{sock_path}", seed=7) as server:
        assert stat.S_IMODE(os.stat(sock_path).st_mode) == 0o600  # owner only
        with RolloutClient(server.address, timeout=10) as client:
            started = client.instruct(BANANA)
            assert started == {"status": "started", "episode": 0, "instruction": BANANA}
            result = client.result()
    # Banana -> the stub pushes +1 per step -> the goal of 3 is reached at step 3.
    assert result == {
        "status": "success",
        "episode": 0,
        "instruction": BANANA,
        "reason": "success",
        "steps": 3,
    }
    assert policy.calls == [(BANANA, 0.0), (BANANA, 1.0), (BANANA, 2.0)]  # task and obs per step
    assert policy.resets == 1
    assert env.unwrapped.resets == [{"seed": 7, "instruction": BANANA}]
    assert env.unwrapped.task_description == BANANA
    assert not sock_path.exists()  # removed on close


def test_tcp_failure_at_the_step_limit_then_a_second_episode(make_push_env, policy, serving):
    env = make_push_env(max_steps=50)
    with serving(env, policy, "tcp:127.0.0.1:0", max_steps=6, seed=None) as server:
        assert server.address.port > 0  # port 0: the bound port is reported
        with RolloutClient(str(server.address), timeout=10) as client:
            client.instruct(APPLE)  # the stub holds still: never succeeds
            first = client.result()
            client.instruct(BANANA)
            second = client.result()
    assert (first["status"], first["reason"], first["steps"]) == ("failure", "max_steps", 6)
    assert (second["status"], second["episode"], second["steps"]) == ("success", 1, 3)
    assert [r.status for r in server.results] == ["failure", "success"]
    assert env.unwrapped.resets[0]["seed"] is None


def test_done_from_another_connection_ends_the_episode_for_both(make_push_env, policy, serving):
    # A goal that is never reached and a limit that is never hit: only 'done' ends it.
    env = make_push_env(max_steps=10**9, goal=float("inf"))
    with (
        serving(env, policy, "tcp:127.0.0.1:0") as server,
        RolloutClient(server.address, timeout=10) as owner,
        RolloutClient(server.address, timeout=10) as other,
    ):
        owner.instruct(BANANA)
        deadline = time.monotonic() + 30
        while len(policy.calls) < 5:  # it runs
            assert time.monotonic() < deadline, f"{len(policy.calls)} policy calls in 30 s, not 5"
            time.sleep(0.01)
        by_done = other.done()
        to_owner = owner.result()
    assert by_done == to_owner
    assert (by_done["status"], by_done["reason"]) == ("failure", "done")
    assert by_done["steps"] >= 5 and by_done["steps"] in (len(policy.calls), len(policy.calls) - 1)


def test_done_from_the_owner_is_answered_once(make_push_env, policy, serving):
    env = make_push_env(max_steps=10**9, goal=3.0)  # apple: never reached; banana: 3 steps
    with (
        serving(env, policy, "tcp:127.0.0.1:0") as server,
        RolloutClient(server.address, timeout=10) as client,
    ):
        client.instruct(APPLE)
        assert client.done()["reason"] == "done"
        client.instruct(BANANA)  # the next reply is this one's, not a second result
        assert client.result()["status"] == "success"


def test_errors_are_json_and_the_connection_stays_usable(make_push_env, policy, serving):
    env = make_push_env(max_steps=10**9, goal=float("inf"))
    with (
        serving(env, policy, "tcp:127.0.0.1:0") as server,
        RolloutClient(server.address, timeout=10) as client,
        RolloutClient(server.address, timeout=10) as second,
    ):

        def refused(line: bytes) -> dict:
            client._sock.sendall(line)
            reply = client.read_reply()
            assert reply["status"] == "error", reply
            return reply

        assert refused(b"done\n")["error"] == "not_running"
        assert refused(b"   \n")["error"] == "empty"
        assert refused(b"\xff\xfe banana\n")["error"] == "bad_encoding"
        assert refused(b"x" * 5000 + b"\n")["error"] == "line_too_long"
        unknown = refused(b"Juggle the bananas.\n")
        assert unknown["error"] == "bad_instruction" and BANANA in unknown["message"]
        assert unknown["request"] == "Juggle the bananas."

        client.instruct(APPLE)  # still usable; and now busy for everyone
        with pytest.raises(RolloutError) as busy:
            second.instruct(BANANA)
        assert busy.value.code == "busy" and APPLE in busy.value.reply["message"]
        assert client.done()["status"] == "failure"
    assert env.unwrapped.resets == [{"seed": 0, "instruction": APPLE}]  # nothing else reset


def test_a_connection_over_the_limit_is_told_so_and_closed(make_push_env, policy, serving):
    """``max_connections`` held: one more gets the ``too_many_connections`` reply, then EOF;
    once one of them leaves, a new connection is served again. Loopback TCP only."""
    with serving(make_push_env(), policy, "tcp:127.0.0.1:0", max_connections=2) as server:
        address = ("127.0.0.1", server.address.port)

        def refused() -> tuple[socket.socket, dict | None]:
            """A raw connection that sends nothing, and the reply the server sends unasked
            (None if none came within 2 s: a served connection answers only requests).
            Sending nothing matters: a server closing with our bytes unread would reset the
            connection instead of ending it."""
            sock = socket.create_connection(address, timeout=10)
            sock.settimeout(2.0)
            try:
                line = sock.makefile("rb").readline()
            except TimeoutError:
                return sock, None
            finally:
                sock.settimeout(10)
            return sock, json.loads(line)

        def served(sock: socket.socket) -> dict:
            """The reply to 'done' with no episode running (``not_running`` when served)."""
            sock.sendall(b"done\n")
            return json.loads(sock.makefile("rb").readline())

        held = []
        for _ in range(2):
            sock, unasked = refused()
            assert unasked is None, unasked  # under the limit: served, nothing said unasked
            held.append(sock)
        assert [served(sock)["error"] for sock in held] == ["not_running", "not_running"]
        extra, reply = refused()
        assert reply == {
            "status": "error",
            "error": "too_many_connections",
            "message": "the server holds its maximum of connections",
            "request": None,  # answered on connecting, before reading anything
        }
        assert extra.recv(64) == b""  # closed by the server
        extra.close()
        for sock in held:  # the held ones are still served
            assert served(sock)["error"] == "not_running"
        held.pop().close()
        deadline = time.monotonic() + 10  # the server notices the close on its next poll
        while True:
            sock, unasked = refused()
            if unasked is None:
                break
            assert unasked["error"] == "too_many_connections", unasked
            sock.close()
            assert time.monotonic() < deadline, "a freed connection slot was never reused"
        assert served(sock)["error"] == "not_running"
        sock.close()
        held[0].close()


def test_crlf_lines_and_split_packets(make_push_env, policy, serving, sock_path):
    with (
        serving(make_push_env(), policy, f"unix:{sock_path}") as server,
        RolloutClient(server.address, timeout=10) as client,
    ):
        half = len(BANANA) // 2
        client._sock.sendall(BANANA[:half].encode())
        time.sleep(0.05)
        client._sock.sendall(BANANA[half:].encode() + b"\r\n")
        assert client.read_reply()["instruction"] == BANANA
        assert client.result()["status"] == "success"


def test_episodes_limit_makes_serve_return(make_push_env, policy, sock_path):
    server = RolloutServer(make_push_env(), policy, f"unix:{sock_path}", episodes=2)
    replies = []

    def client():
        with RolloutClient(f"unix:{sock_path}", timeout=10) as c:
            for text in (BANANA, APPLE):
                c.instruct(text)
                replies.append(c.result())

    with server:
        thread = threading.Thread(target=client)
        thread.start()
        results = server.serve()  # returns by itself after two episodes
        thread.join(timeout=10)
    assert [r.instruction for r in results] == [BANANA, APPLE]
    assert [r["status"] for r in replies] == ["success", "failure"]
    assert not sock_path.exists()


def test_stop_mid_episode_aborts_it_and_removes_the_socket(
    make_push_env, policy, serving, sock_path
):
    env = make_push_env(max_steps=10**9, goal=float("inf"))
    with serving(env, policy, f"unix:{sock_path}") as server:
        client = RolloutClient(server.address, timeout=10)
        client.instruct(BANANA)
        server.stop()
        result = client.result()
        client.close()
    assert (result["status"], result["reason"]) == ("aborted", "shutdown")
    assert not sock_path.exists()


def test_sigterm_stops_the_server_cleanly(make_push_env, policy, sock_path):
    env = make_push_env(max_steps=10**9, goal=float("inf"))
    replies = []

    def client_then_signal():
        with RolloutClient(f"unix:{sock_path}", timeout=10) as c:
            replies.append(c.instruct(APPLE))
            os.kill(os.getpid(), signal.SIGTERM)  # handled in the main thread, in serve()
            replies.append(c.result())

    server = RolloutServer(env, policy, f"unix:{sock_path}")
    before = signal.getsignal(signal.SIGTERM)
    with server, stop_on_signals(server) as received:
        thread = threading.Thread(target=client_then_signal)
        thread.start()
        server.serve()
        thread.join(timeout=10)
    assert received == [signal.SIGTERM]
    assert signal.getsignal(signal.SIGTERM) is before  # restored
    assert [r["status"] for r in replies] == ["started", "aborted"]
    assert not sock_path.exists()


def test_unix_socket_path_handling(make_push_env, policy, sock_path):
    # A stale socket file (no server behind it) is replaced.
    stale = socket.socket(socket.AF_UNIX)
    stale.bind(str(sock_path))
    stale.close()
    with RolloutServer(make_push_env(), policy, f"unix:{sock_path}") as first:
        assert sock_path.exists()
        # A live one is not taken over ...
        with pytest.raises(OSError, match="another server is listening"):
            RolloutServer(make_push_env(), policy, f"unix:{sock_path}").open()
        assert first.address.path.exists()
    # ... and a file that is not a socket is never replaced.
    sock_path.write_text("precious")
    with pytest.raises(FileExistsError, match="not a socket"):
        RolloutServer(make_push_env(), policy, f"unix:{sock_path}").open()
    assert sock_path.read_text() == "precious"


def test_a_replaced_socket_file_is_not_removed_by_the_old_server(make_push_env, policy, sock_path):
    server = RolloutServer(make_push_env(), policy, f"unix:{sock_path}")
    server.open()
    sock_path.unlink()
    sock_path.write_text("someone else's")
    server.close()
    assert sock_path.read_text() == "someone else's"


@pytest.mark.parametrize("host", ["0.0.0.0", "192.0.2.1", "example.invalid"])
def test_non_loopback_tcp_is_refused_unless_allowed(make_push_env, policy, host):
    with pytest.raises(PermissionError, match="not a loopback address"):
        RolloutServer(make_push_env(), policy, f"tcp:{host}:0")


def test_non_loopback_bind_when_forced(make_push_env, policy):
    with (
        RolloutServer(make_push_env(), policy, "tcp:0.0.0.0:0", allow_remote=True) as server,
        RolloutClient(f"tcp:127.0.0.1:{server.address.port}", timeout=10) as client,
    ):
        assert client.address.port == server.address.port


def test_loopback_names_are_local():
    assert Address.parse("tcp:localhost:1").is_local()
    assert Address.parse("tcp:[::1]:1").is_local()
    assert Address.parse("unix:/tmp/x.sock").is_local()


def test_without_a_step_limit_max_steps_is_required(policy, make_push_env):
    with pytest.raises(ValueError, match="max_steps"):
        RolloutServer(make_push_env().unwrapped, policy, "tcp:127.0.0.1:0")
    server = RolloutServer(make_push_env(max_steps=40), policy, "tcp:127.0.0.1:0", max_steps=90)
    assert server.max_steps == 40  # the tighter of the two


def test_policy_exception_ends_the_episode_with_an_error(make_push_env, serving):
    class Broken:
        def reset(self):
            pass

        def act(self, observation, instruction):
            raise RuntimeError("camera unplugged")

    with (
        serving(make_push_env(), Broken(), "tcp:127.0.0.1:0") as server,
        RolloutClient(server.address, timeout=10) as client,
    ):
        client.instruct(BANANA)
        with pytest.raises(RolloutError, match="camera unplugged") as err:
            client.result()
        assert err.value.reply["episode"] == 0 and err.value.code == "internal"
        client.instruct(APPLE)  # the server goes on
        with pytest.raises(RolloutError):
            client.result()
