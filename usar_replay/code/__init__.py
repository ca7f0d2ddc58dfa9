"""code: the code submission graded (the course's second 60 points), copies across a class
found, the report checked as flags for a person.

Modules, one job each: ``sources`` (a team's files read without trusting them), ``cxx`` (C++
comments and code told apart), ``comments`` (commented-out code), ``tools`` (an external tool
run on a copy, sandboxed and limited, or one line naming its Debian package), ``doxygen``
(documentation coverage, classes, main() from doxygen's XML), ``docs_own`` (does the committed
HTML document these sources), ``cppcheck`` (unused functions, unread variables, lint),
``style`` (clang-format against the course's style), ``compile`` (a syntax-only build with
warnings), ``template`` (the course template as boilerplate), ``similarity`` (winnowing across
a class), ``report_pdf`` (the report's flags), ``rubric`` (the rubric as TOML data, scored),
``grade`` (one package's grade) and ``output`` (table, JSON, CSV). It may import core, node
(the kernel sandbox) and ros1 (package discovery).
"""
