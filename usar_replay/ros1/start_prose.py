"""Commands as a person reads them in a team's prose (issue 51): what a TA types from a line.

Why: students write their start every way a sentence allows: ``6.Open another terminal and
run "rosrun final_project final_project_node" to run the executable scripts.``, ``4. Run
command "rosrun final_project final_project_node"``, in backquotes, in a fenced code block,
after a prompt (``$``, ``#``, ``>``), a bullet or a number, with a full stop after it. A TA
reads each of them as the command inside the quotes, never the closing quote as part of the
executable's name. Read wrong, a team is started with a name its package does not have and
is blamed for a crash no code of its ran.

The one idea written here is where a command's text begins and ends on a line: at each
command word (``roslaunch``, ``rosrun``, ``rosservice call``, ``rostopic pub``); inside the
quotes it follows (``"``, ``'``, backquote, a prompt between them allowed), to their closing
quote (a quote of the same kind that opens inside, ``"rosservice call /start "data: true""``,
is nested), else to the next command word or the line's end. The words themselves are the
shell's (:mod:`shlex`, in POSIX mode with the shell's operators as tokens): a command ends at
``;``, ``&&``, ``||``, ``|``, ``&`` or a redirection, quotes are removed as the shell removes
them, ``#`` starts a comment.
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass

__all__ = ["THIRD_COMMANDS", "Command", "clean_name", "parse_commands", "third_command"]

_COMMAND = re.compile(r"\b(roslaunch|rosrun|rosservice\s+call|rostopic\s+pub)\b")
_QUOTES = "\"'`"
_PROMPTS = "$#>"
_PUNCT = frozenset("();<>|&")
_TRAILING = ".,;:!?"
_TYPOGRAPHIC = str.maketrans("\u201c\u201d\u201e\u2018\u2019\u201a", "\"\"\"'''")
"""A word processor's quotes (a handout pasted into ``instructions.txt``) read as the
keyboard's."""
_NAME = re.compile(r"[\w./~+-]*")
THIRD_COMMANDS = (("rosservice", "call"), ("rostopic", "pub"))
"""The TA's third commands (the handout's ``rosservice call /start "data: true"``); no other
command of a team's is ever run."""


@dataclass(frozen=True, slots=True)
class Command:
    """One command of a text: its words and its line number (1-based)."""

    words: tuple[str, ...]
    line: int


def _opening_quote(line: str, at: int) -> int:
    """Where the quote a command word at ``at`` stands in lies (a prompt between them
    allowed), or -1."""
    j = at - 1
    while j >= 0 and line[j].isspace():
        j -= 1
    if j >= 0 and line[j] in _PROMPTS:
        j -= 1
        while j >= 0 and line[j].isspace():
            j -= 1
    return j if j >= 0 and line[j] in _QUOTES else -1


def _closing(line: str, at: int, quote: str) -> int:
    """Where the quote opened before ``at`` closes (the line's end when it does not): a quote
    of the same kind with a space before it and a word after it opens a nested one."""
    depth = 1
    for k in range(at, len(line)):
        if line[k] != quote:
            continue
        if quote == "`":  # backquotes do not nest
            return k
        before = line[k - 1]
        after = line[k + 1] if k + 1 < len(line) else ""
        if (before.isspace() or before in "=(:[{") and after and not after.isspace():
            depth += 1
        else:
            depth -= 1
            if depth == 0:
                return k
    return len(line)


def _spans(line: str) -> list[str]:
    """The command texts of one line, in order (see the module doc)."""
    matches = list(_COMMAND.finditer(line))
    out: list[str] = []
    end = 0
    for i, match in enumerate(matches):
        at = match.start()
        if at < end:  # inside the quotes of the one before: its operators split it
            continue
        quote = _opening_quote(line, at)
        if quote >= 0:
            end = _closing(line, at, line[quote])
            out.append(line[at:end])
            end += 1
        else:  # to the next command (or the quote it stands in), or the line's end
            end = len(line)
            if i + 1 < len(matches):
                following = matches[i + 1].start()
                opened = _opening_quote(line, following)
                end = opened if opened >= 0 else following
            text = line[at:end]
            out.append(text.rstrip().rstrip(_TRAILING) if end == len(line) else text)
    return out


def _tokens(text: str) -> list[str]:
    """The shell's words and operators of ``text``; where a quote is left open (prose: an
    apostrophe), the words as written, quotes and all (:func:`clean_name` reads names)."""
    lexer = shlex.shlex(text, posix=True, punctuation_chars=True)
    lexer.whitespace_split = True
    try:
        return list(lexer)
    except ValueError:
        return text.split()


def _pieces(tokens: list[str]) -> list[list[str]]:
    """``tokens`` cut at the shell's operators (a redirection's file is a piece of its own)."""
    out: list[list[str]] = [[]]
    for token in tokens:
        if token and set(token) <= _PUNCT:
            out.append([])
        else:
            out[-1].append(token)
    return [p for p in out if p]


def _is_command(words: list[str]) -> bool:
    if not words:
        return False
    if words[0] in ("roslaunch", "rosrun"):
        return True
    return tuple(words[:2]) in THIRD_COMMANDS


def parse_commands(text: str) -> list[Command]:
    """Every ``roslaunch``, ``rosrun``, ``rosservice call`` and ``rostopic pub`` command of a
    text, in order, as a person reads them (the module doc)."""
    out: list[Command] = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not _COMMAND.search(line):
            continue
        line = line.translate(_TYPOGRAPHIC)
        for span in _spans(line):
            for piece in _pieces(_tokens(span)):
                if _is_command(piece):
                    out.append(Command(tuple(piece), number))
    return out


def clean_name(word: str) -> str:
    """A package, executable or launch file's name as a word of prose writes it: what lies
    before a quote, a bracket, markup or a tag (``final_project_node"`` -> ``final_project_node``,
    ``go.launch**`` -> ``go.launch``), trailing punctuation left out (``go.launch.``)."""
    match = _NAME.match(word)
    return (match.group(0) if match else "").rstrip(_TRAILING)


def third_command(text: str) -> str | None:
    """``text`` as one TA's third command (``rosservice call`` or ``rostopic pub``, its words
    joined as the shell would quote them), or None when it writes none: any other command,
    and everything after an operator (``; rm -rf ~``), is never run."""
    commands = parse_commands(text)
    if not commands or tuple(commands[0].words[:2]) not in THIRD_COMMANDS:
        return None
    return shlex.join(commands[0].words)
