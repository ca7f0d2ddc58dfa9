"""`usar code`'s speed: the default rubric on one package, and similarity across a class of 60
(printed, not asserted; the issue's budget: under 5 s a package, under a minute for 60).

python bench/bench_code.py
"""

from __future__ import annotations

import random
import re
import time
from pathlib import Path

from usar_replay.code import similarity
from usar_replay.code.grade import grade
from usar_replay.code.rubric import default_rubric
from usar_replay.code.sources import Source, read_submission
from usar_replay.code.template import read_template

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "examples" / "ros1" / "usar_course"
TEMPLATE = ROOT / "examples" / "ros1" / "course_template"


def _variant(sources: tuple[Source, ...], seed: int) -> list[Source]:
    """A team of the synthetic class: the package's code with its identifiers renamed and
    numbers changed per team, and as many lines again of functions of its own."""
    rng = random.Random(seed)
    words = sorted({w for s in sources for w in re.findall(r"\b[a-z_]{5,}\b", s.text)})
    renames = {w: f"{w}_{seed}" for w in rng.sample(words, len(words) // 3)}
    pattern = re.compile(r"\b(" + "|".join(map(re.escape, renames)) + r")\b")
    out = [Source(s.rel, pattern.sub(lambda m: renames[m.group(1)], s.text)) for s in sources]
    extra = []
    for k in range(40):
        a, b, c = (rng.randint(1, 99) for _ in range(3))
        extra.append(
            f"double team{seed}_f{k}(double x, int n) {{\n  double acc = {a}.0;\n"
            f"  for (int i = 0; i < n * {b}; ++i) {{\n    acc += x * i / {c}.0;\n"
            f"    if (acc > {a * b}) {{\n      acc -= {c};\n    }}\n  }}\n  return acc;\n}}\n"
        )
    rng.shuffle(extra)
    return [*out, Source("src/extra.cpp", "\n".join(extra))]


def main() -> None:
    rubric = default_rubric()
    tmpl = read_template(TEMPLATE)
    sub = read_submission(PACKAGE)
    grade(sub, rubric, tmpl)  # warm the tools' pages
    runs = []
    for _ in range(3):
        t0 = time.perf_counter()
        g = grade(sub, rubric, tmpl)
        runs.append(time.perf_counter() - t0)
    lines = sum(s.lines for s in sub.sources)
    print(f"default rubric, one package ({len(sub.sources)} files, {lines} lines): "
          f"{min(runs):.2f} s best, {max(runs):.2f} s worst of 3 "
          f"({g.points:g}/{g.max_points:g} points)")  # fmt: skip
    teams = [_variant(sub.sources, seed) for seed in range(60)]
    t0 = time.perf_counter()
    bp = similarity.boilerplate(tmpl.sources)
    prints = [similarity.prints(f"team{k:02d}", t, bp) for k, t in enumerate(teams)]
    fp = time.perf_counter() - t0
    t0 = time.perf_counter()
    pairs = similarity.similar(prints)
    cmp = time.perf_counter() - t0
    lines60 = sum(s.lines for t in teams for s in t)
    print(f"similarity, class of 60 ({lines60} lines): fingerprints {fp:.1f} s, "
          f"1770 pairs {cmp:.1f} s, total {fp + cmp:.1f} s ({len(pairs)} pairs listed)")


if __name__ == "__main__":
    main()
