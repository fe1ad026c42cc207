"""clc: the CLC lane detector of Ivanov & Markgraf (2024), built on ``rld``'s shared geometry,
constraints and costs: a search graph over the cones, the depth-first enumeration of path pairs
under geometric constraints (``clc.search``, numba kernels in ``clc.search_kernels``), and a
ranker that picks the most likely lane (``clc.ranker``). Use it through
``rld.solve_lane(..., method="clc")`` or ``rld.LaneSolver(method="clc")``; see docs/clc.md."""
