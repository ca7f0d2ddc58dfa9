"""sandbox: confining untrusted code, whoever runs it (a mission, a ROS 1 graph, a build, a tool).

Why a layer of its own: the mission process, ``ros1/`` (build and graph), ``code/`` (doxygen,
cppcheck, g++ on a team's files) and ``batch/`` (CPU sets per job) all need the same confinement,
and none of them needs the node API. ``kernel_sandbox`` (bubblewrap: namespaces, a read-only
root, seccomp, per-run limits), ``confinement`` (the one policy: is untrusted code confined
here?), ``cgroups`` (one face over ``cgroup_v1`` and ``cgroup_v2``: a run's cgroups, chosen by
the mount; v2 in a subtree delegated to usar), ``container`` (which container usar runs in and
the run flags it lacks), ``kernel_pools`` (inotify/fanotify bounded, keys refused),
``cpu_sets`` (each run's own CPUs and its cgroup, claimed machine-wide), ``run_folder`` (the run's
size-limited writable folder), ``hide`` (what a run may not see) and ``audit_guard`` (the
in-process guard of audit hooks, a second layer). It imports only ``core``; a mission process
loads it, so it loads no pybullet, mcap or rerun.
"""
