"""The similar pairs as an HTML page: the matching passages side by side, for a person.

Why: a similarity score alone is an accusation without evidence; a grader decides from the
passages. Every team's text is escaped (:func:`~usar_replay.core.safe_text.html_text`:
controls shown, then ``html.escape``): a submission's code is anyone's, and
it must not script the grader's browser. The page is self-contained (no script, no remote
resource) and deterministic (sorted, no clock).
"""

from __future__ import annotations

from collections.abc import Sequence

from usar_replay.code.similarity import Pair
from usar_replay.core.safe_text import html_text

__all__ = ["pairs_html"]

_STYLE = (
    "body{font-family:sans-serif;margin:1em}table{border-collapse:collapse;width:100%}"
    "td{vertical-align:top;border:1px solid #ccc;padding:4px;width:50%}"
    "pre{white-space:pre-wrap;font-size:12px;margin:0}"
)


def pairs_html(pairs: Sequence[Pair], threshold: float) -> str:
    """The page: each pair (score first), its passages in two columns."""
    esc = html_text  # controls escaped, then HTML's escapes
    out = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'>",
        "<meta http-equiv='Content-Security-Policy' content=\"default-src 'none'; "
        "style-src 'unsafe-inline'\">",
        f"<title>usar code: similar pairs</title><style>{_STYLE}</style></head><body>",
        f"<h1>Similar pairs (score &ge; {threshold:g})</h1>",
        "<p>For a person to review: a score is never points. The course template's code is "
        "boilerplate and does not count.</p>",
    ]
    if not pairs:
        out.append("<p>No pair of teams scores that high.</p>")
    for p in pairs:
        out.append(f"<h2>{esc(p.a)} ~ {esc(p.b)}: {p.score:.2f}</h2><table>")
        out.append(f"<tr><th>{esc(p.a)}</th><th>{esc(p.b)}</th></tr>")
        for x in p.passages:
            out.append(
                f"<tr><td>{esc(x.a)}<pre>{esc(x.a_text)}</pre></td>"
                f"<td>{esc(x.b)}<pre>{esc(x.b_text)}</pre></td></tr>"
            )
        out.append("</table>")
    out.append("</body></html>")
    return "\n".join(out) + "\n"
