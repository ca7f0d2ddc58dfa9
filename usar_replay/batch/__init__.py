"""batch: grading a class.

``plan`` (submissions, worlds, the manifest), ``engines`` (local pool, Ray), ``run_one`` (one
run in its own process), ``driver`` (the resumable loop and its progress) and ``classreport``
(summary, CSV, Gradescope). It may import every layer but ``viewer`` and ``cli``.
"""
