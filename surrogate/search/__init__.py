"""Inverse design: the search over the design box for designs that meet a target, ranked
(``search_designs`` in ``surrogate.search.design_search``, which runs the other modules
in order), and what a target is and what an inverse design answers, for the box search
and the exponential model's grid alike (``design_target``, ``design_result``).
docs/surrogate.md describes the targets, objectives and method; docs/architecture.md
lists the modules."""
