"""The chain's physics: what a chain of given weight hangs like between a hook and an anchor.

:mod:`.catenary` closed forms and the uplift root (arrays and plain floats); :mod:`.inextensible`
problems 1-5 with validation and a status per element; :mod:`.elastic` the elastic chain (EA)
and the rule that keeps the inextensible model; :mod:`.fixed_length` a chain of fixed length at
a span; :mod:`.point_loads` a chain with clump weights and buoys, :mod:`.point_load_table` its
surrogate for the live dock estimate; :mod:`.solve` ``solve()``, the one entry; :mod:`.result`
its result type and statuses; :mod:`.fused_kernel` the optional C kernel of problems 3 and 4
(``_fused_kernel.c``).

SI units (N, N/m, m). May import nothing else of the project: the bottom room of the core.
"""
