"""Key sources: a real terminal reader on a pseudo-terminal, escape sequences, scripts."""

from __future__ import annotations

import os
import sys
import termios
import types

import pytest

from rmb_lerobot.envs.teleop.keys import (
    NoKeySource,
    PynputKeySource,
    ScriptedKeySource,
    TerminalKeySource,
    make_key_source,
    parse_keys,
)


@pytest.fixture
def pty():
    """A pseudo-terminal: write to ``master`` what a person would type into ``slave``."""
    master, slave = os.openpty()
    yield master, slave
    os.close(master)
    os.close(slave)


def test_escape_sequences_become_key_names():
    assert parse_keys("wA\x1b[A\x1b[D\t \x1b") == (["w", "a", "up", "left", "tab", "space"], "\x1b")
    assert parse_keys("\x1bOB\x1b[3~n") == (["down", "delete", "n"], "")
    assert parse_keys("\x1b[15~q") == (["q"], "")  # an unknown sequence (F5) is skipped
    assert parse_keys("s\x1b[") == (["s"], "\x1b[")  # cut short: kept for the next read
    assert parse_keys("\x1bn") == (["esc", "n"], "")


def test_terminal_reader_reads_presses_from_a_pty_and_restores_it(pty):
    master, slave = pty
    before = termios.tcgetattr(slave)
    with TerminalKeySource(slave) as keys:
        raw = termios.tcgetattr(slave)
        assert not raw[3] & termios.ICANON and not raw[3] & termios.ECHO
        assert raw[3] & termios.ISIG  # Ctrl-C still sends SIGINT
        assert keys.poll() == []
        os.write(master, b"nW\x1b[C")
        assert keys.poll() == ["n", "w", "right"]
        os.write(master, b"\x1b")  # Esc alone: reported once no sequence follows
        assert keys.poll() == ["esc"]
        assert keys.poll() == []
    assert termios.tcgetattr(slave) == before


def test_terminal_is_restored_when_the_loop_raises(pty):
    _, slave = pty
    before = termios.tcgetattr(slave)
    with pytest.raises(RuntimeError, match="boom"), TerminalKeySource(slave):
        raise RuntimeError("boom")
    assert termios.tcgetattr(slave) == before


def test_terminal_reader_refuses_what_is_not_a_terminal(tmp_path):
    with (tmp_path / "f").open("w") as file, pytest.raises(OSError, match="not a terminal"):
        TerminalKeySource(file.fileno())


def test_scripted_keys_arrive_at_their_poll_then_esc():
    keys = ScriptedKeySource([(2, "s"), (0, "n"), (2, "w")])
    assert [keys.poll() for _ in range(5)] == [["n"], [], ["s", "w"], ["esc"], []]
    assert ScriptedKeySource([(0, "n")], then=()).poll() == ["n"]


def test_key_source_choice():
    assert isinstance(make_key_source("none"), NoKeySource)
    with pytest.raises(ValueError, match="key source must be one of"):
        make_key_source("joystick")


class FakeListener:
    """pynput.keyboard.Listener's surface: a thread calling ``on_press`` for each key."""

    def __init__(self, on_press):
        self.on_press, self.running = on_press, False

    def start(self):
        self.running = True

    def stop(self):
        self.running = False


def test_pynput_keys_are_named_like_the_terminals(monkeypatch):
    keyboard = types.SimpleNamespace(Listener=FakeListener)
    monkeypatch.setitem(sys.modules, "pynput", types.SimpleNamespace(keyboard=keyboard))
    source = PynputKeySource()
    assert source._listener.running
    press = source._listener.on_press
    press(types.SimpleNamespace(char="W"))
    press(types.SimpleNamespace(char=None, name="esc"))
    press(types.SimpleNamespace(char=None, name="tab"))
    press(types.SimpleNamespace(char=None, name="shift"))  # not a key anything uses
    press(types.SimpleNamespace(char=" "))
    assert source.poll() == ["w", "esc", "tab", "space"]
    assert source.poll() == []
    source.close()
    assert not source._listener.running


def test_without_pynput_the_error_names_the_package_and_the_terminal(monkeypatch):
    monkeypatch.setitem(sys.modules, "pynput", None)
    with pytest.raises(ImportError, match=r"pip install pynput.*--keys terminal"):
        PynputKeySource()
