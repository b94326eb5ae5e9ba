"""The bench report: one HTML page from a results folder (`cramlite report DIR`, and the
end of `cramlite bench`): run parameters, summary, tests, plots, a top-down map per setup
with the driven paths and fetch orders, and per trial of interest a timeline of its task
tree, its steps and, with traces, its replay."""

from cramlite.report.build import build_report

__all__ = ["build_report"]
