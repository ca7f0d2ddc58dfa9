"""viewer: what a person sees of a run in rerun.

``scene`` (what to show, pure), ``view`` (the rerun emission and layout; the only rerun
importer) and ``viewer_process`` (where a view goes, and the ``rerun`` viewer as a child
process). It may import ``core``, ``world``, ``log`` and ``grading``.
"""
