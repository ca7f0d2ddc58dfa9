"""code/similarity: a renamed, reordered copy is found; sharing only the template is not."""

from __future__ import annotations

import codetools

from usar_replay.code.similarity import THRESHOLD, boilerplate, prints, similar
from usar_replay.code.sources import Source


def _alpha() -> list[Source]:
    return [Source("include/alpha/robots.h", codetools.ALPHA_H),
            Source("src/robots.cpp", codetools.ALPHA_CPP),
            Source("src/main.cpp", codetools.ALPHA_MAIN)]  # fmt: skip


def _copy() -> list[Source]:
    return [Source("include/gang/robots.h", codetools.renamed(codetools.ALPHA_H)),
            Source("src/robots.cpp", codetools.renamed(codetools._reordered(codetools.ALPHA_CPP))),
            Source("src/main.cpp", codetools.renamed(codetools.ALPHA_MAIN))]  # fmt: skip


def test_a_renamed_reordered_copy_is_listed_with_its_passages() -> None:
    copy = _copy()
    assert "Scout" in copy[0].text and "Explorer" not in copy[0].text
    pairs = similar([prints("alpha", _alpha()), prints("copy", copy)])
    assert [(p.a, p.b) for p in pairs] == [("alpha", "copy")]
    assert pairs[0].score >= 0.85
    first = pairs[0].passages[0]
    assert first.a.split(":")[0] in {"src/robots.cpp", "include/alpha/robots.h", "src/main.cpp"}
    assert first.a_text and first.b_text


def test_two_teams_sharing_only_the_template_are_not_listed() -> None:
    tmpl = [Source("src/main.cpp", codetools.TEMPLATE_MAIN)]
    a = [Source("src/main.cpp", codetools.TEMPLATE_MAIN), Source("src/b.cpp", codetools.BETA_MAIN)]
    b = [Source("src/main.cpp", codetools.TEMPLATE_MAIN),
         Source("src/c.cpp", codetools.BORROWED_MAIN)]  # fmt: skip
    bp = boilerplate(tmpl)
    assert similar([prints("a", a, bp), prints("b", b, bp)]) == []
    # the template as boilerplate is what keeps them apart
    without = similar([prints("a", a), prints("b", b)])
    assert [(p.a, p.b) for p in without] == [("a", "b")] and without[0].score >= THRESHOLD
    with_bp = similar([prints("a", a, bp), prints("b", b, bp)], threshold=0.0)
    assert all(p.score < THRESHOLD for p in with_bp)


def test_a_team_with_nothing_of_its_own_is_compared_with_nobody() -> None:
    tmpl = [Source("src/main.cpp", codetools.TEMPLATE_MAIN)]
    bp = boilerplate(tmpl)
    assert similar([prints("a", tmpl, bp), prints("b", tmpl, bp)], threshold=0.0) == []


def test_the_order_of_teams_changes_nothing() -> None:
    teams = [prints("z", _copy()), prints("alpha", _alpha()),
             prints("b", [Source("m.cpp", codetools.BETA_MAIN)])]  # fmt: skip
    assert similar(teams) == similar(list(reversed(teams)))


def test_the_score_is_the_same_in_every_process() -> None:
    """Python's ``hash()`` is salted per process; the fingerprints must not depend on it."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    code = (
        "import codetools\n"
        "from usar_replay.code.similarity import prints, similar\n"
        "from usar_replay.code.sources import Source\n"
        "a = [Source('m.cpp', codetools.ALPHA_CPP)]\n"
        "b = [Source('m.cpp', codetools.renamed(codetools._reordered(codetools.ALPHA_CPP)))]\n"
        "print(similar([prints('a', a), prints('b', b)], 0.0)[0].score)\n"
    )
    tests = Path(__file__).resolve().parents[1]
    path = os.pathsep.join([str(tests), str(tests.parent), os.environ.get("PYTHONPATH", "")])
    got = {
        subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                       env={**os.environ, "PYTHONHASHSEED": seed, "PYTHONPATH": path},
                       timeout=120).stdout.strip()
        for seed in ("1", "2", "3")
    }  # fmt: skip
    assert len(got) == 1 and float(got.pop()) > 0.8


def _cosmetic(text: str) -> str:
    """Every statement ends ``; ;`` (issue 50: .393 before the stream was normalised), the
    comments go, literals change, ``this->`` and redundant parentheses are added."""
    import re

    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r";(\s*\n)", r"; ;\1", text)
    text = re.sub(r"\b(\d+)\.(\d+)\b", r"\2.\1", text)
    text = re.sub(r"\breturn ([^;]+);", r"return (\1);", text)
    return text


def test_cosmetic_edits_of_a_copy_keep_it_listed() -> None:
    """``; ;``, comments, literals, renamed identifiers and reordered functions: the copy is
    still listed, at about the plain copy's score (issue 50)."""
    alpha = _alpha()
    edited = [Source(s.rel, _cosmetic(s.text)) for s in _copy()]
    assert "; ;" in edited[2].text
    [pair] = similar([prints("alpha", alpha), prints("edited", edited)])
    [plain] = similar([prints("alpha", alpha), prints("copy", _copy())])
    assert pair.score >= THRESHOLD and pair.score >= plain.score - 0.05
    semis = [Source(s.rel, _cosmetic(s.text)) for s in alpha]
    assert similar([prints("alpha", alpha), prints("semis", semis)])[0].score == 1.0
