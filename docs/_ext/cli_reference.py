"""Sphinx directive ``.. visprim-commands::``: the command reference, read from the parsers.

It calls :func:`visprim.cli.main.build_parser` at build time and renders, for every
command in help order, its description, its usage line and each option group with each
option's help, so that the page cannot drift from ``visprim COMMAND --help``.
"""

from __future__ import annotations

import argparse
import re
from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

_SPECIAL = re.compile(r"([\\`*|_\[\]<>])")


def _text(s: str | None) -> str:
    """``s`` on one line with every reStructuredText markup character escaped."""
    return _SPECIAL.sub(r"\\\1", " ".join((s or "").split()))


def _invocation(action: argparse.Action) -> str:
    """``--out MODEL`` / ``-v, --verbose`` / ``DATA``: how the option is written."""
    if not action.option_strings:
        return str(action.metavar or action.dest)
    if action.nargs == 0:
        return ", ".join(action.option_strings)
    if action.metavar is not None:
        value = str(action.metavar)
    elif action.choices is not None:
        value = "{" + ",".join(str(c) for c in action.choices) + "}"
    else:
        value = action.dest.upper()
    if action.nargs == "?":
        value = f"[{value}]"
    return ", ".join(f"{o} {value}" for o in action.option_strings)


def _help(action: argparse.Action) -> str:
    text = action.help or ""
    if text == argparse.SUPPRESS:
        return ""
    params: dict[str, Any] = {"prog": "visprim", "default": action.default}
    try:
        return text % params
    except (KeyError, TypeError, ValueError):
        return text


def _command_lines(name: str, parser: argparse.ArgumentParser, summary: str) -> list[str]:
    title = f"visprim {name}"
    lines = [f".. _cmd-{name}:", "", title, "-" * len(title), ""]
    if parser.description or summary:
        lines += [_text(parser.description or summary), ""]
    usage = parser.format_usage().removeprefix("usage: ").rstrip()
    lines += [".. code-block:: text", ""] + ["   " + u for u in usage.splitlines()] + [""]
    for group in parser._action_groups:
        actions = [a for a in group._group_actions if not isinstance(a, argparse._HelpAction)]
        if not actions:
            continue
        heading = {"positional arguments": "arguments", "options": "options"}.get(
            str(group.title), str(group.title)
        )
        lines += [f".. rubric:: {_text(heading)}", ""]
        for action in actions:
            help_text = _text(_help(action)) or "(no help)"
            hidden = action.metavar is not None and action.option_strings
            if hidden and action.choices is not None and not isinstance(action.choices, dict):
                # The usage shows a metavar, not the choices: list them.
                choices = ", ".join(f"``{c}``" for c in action.choices)
                help_text = f"{help_text.rstrip('.')}. One of {choices}."
            lines += [f"``{_invocation(action)}``", f"   {help_text}", ""]
    return lines


class VisprimCommands(SphinxDirective):
    """Every ``visprim`` command with its options, from :func:`build_parser`."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        from visprim.cli.main import build_parser

        parser = build_parser()
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        summaries = {str(c.dest): str(c.help or "") for c in sub._choices_actions}
        lines: list[str] = []
        for name, command in sub.choices.items():
            lines += _command_lines(name, command, summaries.get(name, ""))
        node = nodes.section()
        node.document = self.state.document
        nested_parse_with_titles(self.state, StringList(lines, source="visprim.cli"), node)
        return list(node.children)


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("visprim-commands", VisprimCommands)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
