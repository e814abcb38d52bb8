"""The layout (SPEC §4): segments, connections with joint kinds, the state graph, conflicts and lint."""

from fleetsim.layout.conflicts import ConflictSets, all_pairs_conflicts
from fleetsim.layout.continuations import Continuation
from fleetsim.layout.layout import Connection, Layout, Step, build_layout
from fleetsim.layout.lint import LintFinding, Severity
from fleetsim.layout.segment import Point, Segment, polyline_length

__all__ = [
    "ConflictSets",
    "Connection",
    "Continuation",
    "Layout",
    "LintFinding",
    "Point",
    "Segment",
    "Severity",
    "Step",
    "all_pairs_conflicts",
    "build_layout",
    "polyline_length",
]
