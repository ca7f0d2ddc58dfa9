"""The report, as flags for the grader (never points): its page count, the outline's
sections it has, whether it holds C++ code, spelling errors per page.

Why flags: the report's 60 points are "clarity and quality", which only a person can judge;
what can be measured is what the handout asks in so many words: "not more than 15 pages",
a suggested outline (Introduction, Approach, Challenges, Contributions, Resources), "do not
include C++ code in the report", "check for typos". The PDF is read by poppler's
``pdftotext`` on a copy, in :mod:`usar_replay.code.tools`' sandbox and limits (a PDF is a
program's input like any other); words are checked by hunspell with Debian's en_US dictionary
and the shipped ``allowed_words.txt`` (ROS and C++ terms). The course's handout, which the
template ships in ``doc/``, is not a report: a PDF that is the template's (same bytes) or reads
as the handout (its "Grading Rubric" and "Deliverables" sections) is passed over.

Why the report is chosen before it is read: a team may hold any number of PDFs of any page
count (six of 1,500 pages sharing one content stream took pdftotext 30 s each: issue 50). So
each candidate is first looked at cheaply, ``pdfinfo`` (the page count) and ``pdftotext -l 1``
(the first page), at most the team's budget of PDFs (:mod:`usar_replay.code.budget`), and only
the one chosen by its name and first page is read, its first :data:`READ_PAGES` pages.
"""

from __future__ import annotations

import os
import re
import tempfile
import unicodedata
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path, PurePosixPath

from usar_replay.code import budget
from usar_replay.code.sources import Submission
from usar_replay.code.tools import Ran, ToolLimits, missing, run_tool
from usar_replay.core.folder_walk import Entry, shown, stream

__all__ = ["MAX_PAGES", "OUTLINE", "READ_PAGES", "Report", "allowed_words", "find_reports",
           "report", "sections", "cpp_lines", "words"]  # fmt: skip

MAX_PAGES = 15
"""The handout's limit."""
READ_PAGES = 2 * MAX_PAGES
"""Pages of the report whose text is read (twice the limit: a report over it is flagged by
its page count, and its text past that adds nothing a flag needs)."""
OUTLINE: dict[str, re.Pattern[str]] = {
    "Introduction": re.compile(r"introduction|problem statement|overview", re.I),
    "Approach": re.compile(r"approach|methodology|method|implementation|solution", re.I),
    "Challenges": re.compile(r"challenges?|difficulties|problems faced", re.I),
    "Contributions": re.compile(r"contributions?|team members?|division of work", re.I),
    "Resources": re.compile(r"resources|references|bibliography", re.I),
}
"""The handout's suggested outline, and the headings that say each."""
_HEADING = re.compile(r"^\s*(\d+(\.\d+)*\.?|[IVX]+\.)?\s*(?P<title>[A-Za-z][A-Za-z /&-]{2,60})\s*$")
_CPP = re.compile(
    r"#include\s*[<\"]|\bstd::|\bros::|\bint\s+main\s*\(|->\w+\(|\bvoid\s+\w+::\w+\(|"
    r"\w+::\w+\([^)]*\)\s*;|;\s*$"
)
_STRONG = re.compile(r"#include\s*[<\"]|\bstd::\w|\bros::\w|::\w+\(.*\)\s*[;{]")
_WORD = re.compile(r"(?<![\w@/.<:-])[A-Za-z][a-z]+(?:'[a-z]+)?(?![\w@/:>-])")
_MAX_PDF = 64 * 1024 * 1024


@dataclass(frozen=True, slots=True)
class Report:
    file: str | None
    """The report's path in the submission (None: no report found)."""
    pages: int | None = None
    sections: tuple[str, ...] = ()
    missing_sections: tuple[str, ...] = ()
    cpp_code: bool | None = None
    cpp_where: str = ""
    """``page N`` where C++ code is."""
    spelling_per_page: float | None = None
    misspelled: tuple[str, ...] = ()
    """The commonest unknown words (up to ten), for the grader to look at."""
    problems: tuple[str, ...] = field(default=())


def allowed_words() -> frozenset[str]:
    text = resources.files("usar_replay.code").joinpath("allowed_words.txt").read_text()
    return frozenset(
        w.strip().lower() for w in text.splitlines() if w.strip() and not w.startswith("#")
    )


def find_reports(
    sub: Submission, template_pdfs: frozenset[str] = frozenset(), said: list[str] | None = None
) -> list[Entry]:
    """The submission's PDFs that could be its report, the likeliest first (a name that says
    "report", then the largest): links, the template's own and doxygen's output (anything under
    a ``latex/`` or ``html/`` folder: its graphs, its ``refman.pdf``) left out; one over the size
    read is said in ``said``."""
    import hashlib

    out = []
    for e in sub.entries:
        rel = PurePosixPath(shown(e.rel))
        if rel.suffix.lower() != ".pdf" or e.link is not None:
            continue
        if {"latex", "html"} & {part.lower() for part in rel.parts[:-1]}:
            continue
        if e.size > _MAX_PDF:
            if said is not None:
                said.append(f"{shown(e.rel)}: {e.size} bytes, over the {_MAX_PDF} read")
            continue
        h = hashlib.sha256()
        stream(e, h.update)
        if h.hexdigest() not in template_pdfs:
            out.append(e)
    out.sort(key=lambda e: ("report" not in shown(e.rel).lower(), -e.size, e.rel))
    return out


def sections(pages: list[str]) -> list[str]:
    """The outline's sections that a short heading line of the text names, in outline order."""
    found = set()
    for page in pages:
        for line in page.splitlines():
            m = _HEADING.match(line)
            if not m or len(line.split()) > 6:
                continue
            for name, pattern in OUTLINE.items():
                if pattern.fullmatch(m["title"].strip()) or pattern.match(m["title"].strip()):
                    found.add(name)
    return [n for n in OUTLINE if n in found]


def cpp_lines(pages: list[str]) -> tuple[int, str]:
    """(lines that read as C++ code, ``page N`` of the first): a line counts when it has a
    C++-only mark (``#include <``, ``std::``, ``ros::``, ``Class::method(...);``)."""
    count, where = 0, ""
    for n, page in enumerate(pages, 1):
        for line in page.splitlines():
            if _STRONG.search(line):
                count += 1
                where = where or f"page {n}"
    return count, where


def words(page: str) -> list[str]:
    """The words of a page the spelling check looks at: lower-case letters after at most one
    capital (acronyms, camelCase identifiers, paths, e-mail addresses and words with digits
    are left out: they are names, not prose; so are lines of C++ code)."""
    prose = "\n".join(line for line in page.splitlines() if not _STRONG.search(line))
    return [w for w in _WORD.findall(prose) if len(w) >= 3]


def _is_handout(pages: list[str]) -> bool:
    text = "\n".join(pages)
    return "Grading Rubric" in text and "Deliverables" in text and "Getting Help" in text


def _copy_pdf(entry: Entry, dest: Path) -> None:
    fd = os.open(dest, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644)
    with os.fdopen(fd, "wb") as out:
        stream(entry, out.write)


@dataclass(frozen=True, slots=True)
class _Probe:
    """What the cheap look at one PDF saw: its page count and first page's text."""

    entry: Entry
    pages: int | None
    first: str
    problem: str = ""

    def rank(self) -> tuple[bool, bool, bool, int, bytes]:
        """Sort key, likeliest report first: a name that says "report", a first page that
        says it or names a section of the outline, a page count the handout allows, then the
        largest."""
        name = "report" in shown(self.entry.rel).lower()
        said = bool(re.search(r"\breport\b", self.first, re.I)) or bool(sections([self.first]))
        fits = self.pages is not None and self.pages <= MAX_PAGES
        return (not name, not said, not fits, -self.entry.size, self.entry.rel)


def _run_on_copy(entry: Entry, argvs: list[list[str]], limits: ToolLimits | None) -> list[Ran]:
    """Each of ``argvs`` run on one copy of the PDF (``report.pdf``), in order; stops at the
    first that went past a limit."""
    out: list[Ran] = []
    with tempfile.TemporaryDirectory(prefix="usar-pdf-") as tmp:
        work = Path(tmp)
        _copy_pdf(entry, work / "report.pdf")
        for argv in argvs:
            out.append(run_tool(argv, work, limits))
            if out[-1].limit:
                break
    return out


_PROBE = ToolLimits(wall_s=10.0, cpu_s=10)
"""A look at one page is quick (tens of ms); a first page that is not is the team's PDF's."""


def _probe(entry: Entry, limits: ToolLimits | None) -> _Probe:
    """The page count (``pdfinfo``) and the first page's text (``pdftotext -l 1``): both read
    only the page tree and one page, whatever the PDF holds (under :data:`_PROBE`'s limits
    unless ``limits`` are given)."""
    ran = _run_on_copy(
        entry,
        [["pdfinfo", "report.pdf"], ["pdftotext", "-l", "1", "-enc", "UTF-8", "report.pdf", "-"]],
        limits or _PROBE,
    )
    info = ran[0]
    if info.limit:
        return _Probe(entry, None, "", f"pdfinfo exceeded {info.limit}")
    if info.code != 0 or len(ran) < 2:
        return _Probe(entry, None, "", f"pdfinfo could not read it (exit {info.code})")
    found = re.search(r"^Pages:\s+(\d+)\s*$", info.output, re.MULTILINE)
    pages = int(found.group(1)) if found else None
    first = ran[1]
    if first.limit:
        return _Probe(entry, pages, "", f"pdftotext exceeded {first.limit}")
    return _Probe(entry, pages, unicodedata.normalize("NFKC", first.output))


def _read_pdf(entry: Entry, limits: ToolLimits | None) -> tuple[list[str] | None, str]:
    """The text of the first :data:`READ_PAGES` pages, a list of pages."""
    argv = ["pdftotext", "-l", str(READ_PAGES), "-enc", "UTF-8", "report.pdf", "-"]
    [ran] = _run_on_copy(entry, [argv], limits)
    if ran.limit:
        return None, f"pdftotext exceeded {ran.limit}"
    if ran.code != 0:
        return None, f"pdftotext could not read it (exit {ran.code})"
    # NFKC: a ligature (U+FB01 for "fi") is its letters, or "fiducial" reads as "iducial"
    pages = unicodedata.normalize("NFKC", ran.output).split("\f")
    if pages and not pages[-1].strip():
        pages.pop()
    return pages, ""


def _misspelled(all_words: set[str], limits: ToolLimits | None) -> tuple[set[str] | None, str]:
    gone = missing("hunspell")
    if gone:
        return None, gone
    with tempfile.TemporaryDirectory(prefix="usar-spell-") as tmp:
        work = Path(tmp)
        (work / "words.txt").write_text("\n".join(sorted(all_words)) + "\n", encoding="utf-8")
        ran = run_tool(["hunspell", "-l", "-d", "en_US", "words.txt"], work, limits)
    if ran.limit or ran.code != 0:
        return None, f"hunspell {'exceeded ' + ran.limit if ran.limit else 'failed'}"
    return {w.strip() for w in ran.output.splitlines() if w.strip()}, ""


def _chosen(
    candidates: list[Entry], limits: ToolLimits | None, problems: list[str]
) -> list[_Probe]:
    """The candidates the team's budget lets be looked at (:data:`usar_replay.code.budget`:
    PDFs tried), each probed cheaply, likeliest report first; the others said."""
    spend = budget.current()
    probes: list[_Probe] = []
    for n, entry in enumerate(candidates):
        if spend is not None and not spend.pdf():
            left = len(candidates) - n
            problems.append(
                f"{left} more PDF{'s' if left > 1 else ''} not tried "
                f"(a team's budget: {spend.budget.pdfs} PDFs), first {shown(entry.rel)}"
            )
            break
        probe = _probe(entry, limits)
        if probe.problem:
            problems.append(f"{shown(entry.rel)}: {probe.problem}")
        else:
            probes.append(probe)
    return sorted(probes, key=_Probe.rank)


def report(
    sub: Submission, template_pdfs: frozenset[str] = frozenset(), limits: ToolLimits | None = None
) -> Report:
    """The flags of the submission's report: the PDFs that could be one, likeliest first by
    name and size (:func:`find_reports`), as many as the team's budget allows looked at
    cheaply (page count, first page: :func:`_probe`), ranked by what that shows
    (:meth:`_Probe.rank`); the full text (its first :data:`READ_PAGES` pages) is read of the
    first that is not the handout only."""
    problems: list[str] = []
    candidates = find_reports(sub, template_pdfs, problems)
    if not candidates:
        return Report(None, problems=tuple(problems))
    gone = missing("pdftotext") or missing("pdfinfo")
    if gone:
        return Report(shown(candidates[0].rel), problems=(gone,))
    for probe in _chosen(candidates, limits, problems):
        name = shown(probe.entry.rel)
        pages, why = _read_pdf(probe.entry, limits)
        if pages is None:
            problems.append(f"{name}: {why}")
            continue
        if _is_handout(pages):
            continue
        total = probe.pages if probe.pages is not None else len(pages)
        if total > len(pages):
            problems.append(f"{name}: the first {len(pages)} of its {total} pages read")
        found = sections(pages)
        code, where = cpp_lines(pages)
        allowed = allowed_words()
        per_page = [[w for w in words(p) if w.lower() not in allowed] for p in pages]
        bad, why = _misspelled({w for p in per_page for w in p}, limits)
        rate: float | None = None
        common: tuple[str, ...] = ()
        if bad is None:
            problems.append(why)
        else:
            errors = [w for p in per_page for w in p if w in bad]
            rate = round(len(errors) / max(1, len(pages)), 2)
            counts: dict[str, int] = {}
            for w in errors:
                counts[w] = counts.get(w, 0) + 1
            common = tuple(sorted(counts, key=lambda w: (-counts[w], w))[:10])
        return Report(
            name,
            total,
            tuple(found),
            tuple(n for n in OUTLINE if n not in found),
            code >= 3,
            where if code >= 3 else "",
            rate,
            common,
            tuple(problems),
        )
    return Report(None, problems=tuple(problems))
