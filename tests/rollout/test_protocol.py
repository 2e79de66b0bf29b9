"""The wire protocol's pieces: addresses, line splitting, reply lines."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rmb_lerobot.rollout.protocol import (
    MAX_LINE_BYTES,
    Address,
    LineBuffer,
    error_line,
    is_done,
    reply_line,
)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("unix:/tmp/rmb.sock", Address("unix", path=Path("/tmp/rmb.sock"))),
        ("unix:rel/r.sock", Address("unix", path=Path("rel/r.sock"))),
        ("tcp:127.0.0.1:5555", Address("tcp", host="127.0.0.1", port=5555)),
        ("tcp:localhost:0", Address("tcp", host="localhost", port=0)),
        ("tcp:[::1]:7", Address("tcp", host="::1", port=7)),
    ],
)
def test_addresses_parse_and_print_back(text, expected):
    assert Address.parse(text) == expected
    assert str(Address.parse(text)) == text


@pytest.mark.parametrize(
    "text",
    ["/tmp/r.sock", "unix:", "udp:1.2.3.4:5", "tcp:127.0.0.1", "tcp::80", "tcp:h:99999", "tcp:h:x"],
)
def test_bad_addresses_are_refused_with_the_expected_form(text):
    with pytest.raises(ValueError, match="tcp:HOST:PORT"):
        Address.parse(text)


def test_line_buffer_splits_joins_and_drops_overlong_lines():
    lines = LineBuffer()
    assert lines.feed(b"Put the ban") == []
    assert lines.feed(b"ana in the blue basket.\r\ndone\n\n") == [
        b"Put the banana in the blue basket.",
        b"done",
        b"",
    ]
    # An overlong line is reported once, however it arrives, and the next line is intact.
    assert lines.feed(b"x" * (MAX_LINE_BYTES + 1)) == [None]
    assert lines.feed(b"x" * 10_000) == []
    assert lines.feed(b"xx\nnext\n") == [b"next"]
    assert LineBuffer().feed(b"y" * (MAX_LINE_BYTES + 1) + b"\nok\n") == [None, b"ok"]
    assert LineBuffer().feed(b"z" * MAX_LINE_BYTES + b"\n") == [b"z" * MAX_LINE_BYTES]


def test_reply_lines_are_one_json_object_per_line():
    line = reply_line("started", episode=0, instruction="Zeile 1\nZeile 2 \u00e4")
    assert line.endswith(b"\n") and line.count(b"\n") == 1
    expected = {"status": "started", "episode": 0, "instruction": "Zeile 1\nZeile 2 ä"}
    assert json.loads(line) == expected
    assert json.loads(error_line("busy", "m", "r")) == {
        "status": "error",
        "error": "busy",
        "message": "m",
        "request": "r",
    }
    with pytest.raises(ValueError, match="unknown error code"):
        error_line("oops", "m")


def test_done_is_a_command_in_any_case_and_spacing():
    assert is_done("done") and is_done("  DONE ") and is_done("Done")
    assert not is_done("done.") and not is_done("I am done")
