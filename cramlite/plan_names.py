"""The built-in plans and the help text of `--plan` (names only: importing this loads no
simulator)."""

PLAN_NAMES = ("set-table", "clear-table")
PLAN_HELP = ("which plan: set-table (default), clear-table, a plugin's name (`cramlite plans`), "
             "package.module:function or path/to/file.py:function (a plan written with "
             "designators, see examples/)")
