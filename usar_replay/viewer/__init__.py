"""viewer: what a person sees of a run in rerun.

``scene`` (what to show, pure), ``view`` (the rerun emission and the viewer process; the only
rerun importer). It may import ``core``, ``world``, ``log`` and ``grading``.
"""
