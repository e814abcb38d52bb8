"""Contact and clearance: the physical judgement of a run beside the thesis's reservation rule.

:mod:`.geometry` measures vehicle footprints (oriented rectangles) against each other in arrays;
:mod:`.monitor` follows a run step by step: contacts (continuously between steps), the clearance and
near misses. The loop (:mod:`fleetsim.sim.loop`) feeds it every pose; nothing here enters a trace hash.
"""
