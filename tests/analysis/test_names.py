"""Names are names (issue 46): faults, tests and signals may be any identifier. Natural order and axis labels never
assume ``f<number>``; a plot of a model whose faults have other names labels them in full."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np

from fdi_analysis.names import axis_labels, in_order, natural_key, natural_sorted
from fdi_analysis.plots import plot_fault_matrix


def test_natural_order_reads_numbers_as_numbers_and_any_name_as_text() -> None:
    assert natural_sorted(["f10", "f2", "f1"]) == ["f1", "f2", "f10"]
    assert natural_sorted(["tank10_leak", "fuel_flow", "tank2_leak", "f3"]) == [
        "f3", "fuel_flow", "tank2_leak", "tank10_leak"]
    assert natural_sorted(["b", "a", "7", "a1"]) == ["7", "a", "a1", "b"]
    assert natural_key("x") < natural_key("y")


def test_declared_order_first_then_natural_order() -> None:
    """The order the model's author wrote (three_tank: fP, fL1, ..., fS3), names it does not declare after them."""
    order = ["fP", "fL1", "fL2", "fL3", "fC12", "fC23", "fC3", "fS1"]
    assert in_order({"fS1", "fC3", "fP", "fC12"}, order) == ["fP", "fC12", "fC3", "fS1"]
    assert in_order(["x10", "fL1", "x2"], order) == ["fL1", "x2", "x10"]
    assert in_order(["b", "a"], []) == natural_sorted(["b", "a"])


def test_axis_labels_shorten_only_the_paper_names() -> None:
    assert axis_labels(["f1", "f12"]) == ["1", "12"]
    assert axis_labels(["fuel_flow", "f1"]) == ["fuel_flow", "f1"]
    assert axis_labels(["f1a"]) == ["f1a"]
    assert axis_labels([]) == []


def test_a_plot_of_named_faults_keeps_their_names() -> None:
    faults = ["fuel_flow", "f2"]
    fm = np.eye(3, dtype=bool)
    fig = plot_fault_matrix(fm, fm, faults, "named")
    labels = [t.get_text() for t in fig.axes[0].get_xticklabels()]
    assert "fuel_flow" in labels and "uel_flow" not in labels
