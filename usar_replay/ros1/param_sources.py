"""Where each parameter of a loaded launch file came from: its YAML file and its launch file.

Why: ``usar info`` says which of the package's files set what usar took from it (move_base's
goal tolerances, amcl's update thresholds, the course's lookup targets it replaced), e.g.
``param/dwa_local_planner_params.yaml (launch/move_base.launch)``. roslaunch's loaded config
holds each parameter's final value but not its file, so :func:`install` wraps the loader's
few entry points (a ``<rosparam command="load">``, a ``<param>``, a ``<node>``'s private
parameters) to note, as each parameter is added, the YAML file being loaded (if any) and the
launch file being read; the last writer of a key is its source, as roslaunch's own rule is.

The values are roslaunch's own (it read the files, followed ``$(find)`` and the args), inside
the run's sandbox: this module reads no file itself. It runs in Debian's ``/usr/bin/python3``
beside roslaunch (:mod:`.launch_output` loads it by path), so it imports only the standard
library, and roslaunch inside :func:`install`.
"""

from __future__ import annotations

import functools
import os
from typing import Any

__all__ = ["Sources", "install", "label"]

Sources = dict[str, tuple[str, str]]
"""Parameter name -> (YAML file or '', launch file or '') as roslaunch resolved them."""


def install() -> Sources:
    """Wrap roslaunch's loader (once per process) and return the dict it fills as launch files
    are loaded."""
    import roslaunch.config
    import roslaunch.loader
    import roslaunch.xmlloader

    sources: Sources = {}
    yaml_file: list[str] = []
    launch_file: list[str] = []

    def with_launch(method: Any) -> Any:
        @functools.wraps(method)
        def wrapped(self: Any, tag: Any, context: Any, *args: Any, **kwargs: Any) -> Any:
            launch_file.append(str(getattr(context, "filename", "") or ""))
            try:
                return method(self, tag, context, *args, **kwargs)
            finally:
                launch_file.pop()

        return wrapped

    load_rosparam = roslaunch.loader.Loader.load_rosparam

    @functools.wraps(load_rosparam)
    def rosparam(self: Any, context: Any, ros_config: Any, cmd: Any, param: Any, file_: Any,
                 *args: Any, **kwargs: Any) -> Any:
        yaml_file.append(str(file_ or "an inline <rosparam>"))
        launch_file.append(str(getattr(context, "filename", "") or ""))
        try:
            return load_rosparam(self, context, ros_config, cmd, param, file_, *args, **kwargs)
        finally:
            yaml_file.pop()
            launch_file.pop()

    add_param = roslaunch.config.ROSLaunchConfig.add_param

    @functools.wraps(add_param)
    def added(self: Any, p: Any, filename: Any = None, verbose: bool = True) -> Any:
        launch = str(filename or (launch_file[-1] if launch_file else ""))
        sources[str(p.key)] = (yaml_file[-1] if yaml_file else "", launch)
        return add_param(self, p, filename=filename, verbose=verbose)

    xml = roslaunch.xmlloader.XmlLoader
    xml._node_tag = with_launch(xml._node_tag)
    xml._param_tag = with_launch(xml._param_tag)
    roslaunch.loader.Loader.load_rosparam = rosparam
    roslaunch.config.ROSLaunchConfig.add_param = added
    return sources


def label(path: str, package_dir: str) -> str:
    """A file as ``usar info`` shows it: relative to the team's package (``param/x.yaml``),
    else ``PKG/rel`` for a file of another package (the folder holding its ``package.xml``),
    else the path itself."""
    if not path or path.startswith("an inline"):
        return path
    path = os.path.normpath(path)
    if package_dir:
        root = os.path.normpath(package_dir)
        if path.startswith(root + os.sep):
            return os.path.relpath(path, root)
    folder = os.path.dirname(path)
    for _ in range(8):
        if os.path.isfile(os.path.join(folder, "package.xml")):
            return os.path.basename(folder) + "/" + os.path.relpath(path, folder)
        up = os.path.dirname(folder)
        if up == folder:
            break
        folder = up
    return path
