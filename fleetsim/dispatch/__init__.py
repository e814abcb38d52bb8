"""Transport orders at run time, and the dispatcher that assigns them (issue 45; the thesis's §2.3 scheduler).

``protocol``: what a dispatcher is, sees and answers; ``checks``: the rules an answer must keep;
``book``: the orders of one run as they go; ``stream``: where a run's orders come from, step by step.
"""

from fleetsim.dispatch.protocol import Assignment, Dispatcher, OpenOrder, OrderBoard

__all__ = ["Assignment", "Dispatcher", "OpenOrder", "OrderBoard"]
