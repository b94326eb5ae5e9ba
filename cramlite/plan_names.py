"""The plans the command line offers (names only: importing this loads no simulator)."""

PLAN_NAMES = ("set-table", "clear-table")
