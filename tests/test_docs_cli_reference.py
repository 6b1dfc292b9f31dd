"""The command reference of the docs (docs/_ext/cli_reference.py) covers every option of
every command, as the parsers define them."""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import pytest

pytest.importorskip("sphinx")

REPO = Path(__file__).resolve().parents[1]


def _extension():
    path = REPO / "docs" / "_ext" / "cli_reference.py"
    spec = importlib.util.spec_from_file_location("cli_reference", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_every_command_and_option_is_rendered():
    from visprim.cli.main import COMMANDS, build_parser

    ext = _extension()
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert list(sub.choices) == list(COMMANDS)
    for name, command in sub.choices.items():
        text = "\n".join(ext._command_lines(name, command, ""))
        assert f"visprim {name}\n" in text
        for action in command._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            shown = action.option_strings or [str(action.metavar or action.dest)]
            for option in shown:
                assert f"``{option}" in text or f", {option}" in text, (name, option)


def test_help_text_is_escaped():
    ext = _extension()
    assert ext._text("see `visprim learn` and *.bvh_files |x|") == (
        "see \\`visprim learn\\` and \\*.bvh\\_files \\|x\\|"
    )
