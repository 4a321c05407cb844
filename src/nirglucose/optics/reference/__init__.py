"""Validation references: solvers and checks that serve tests and benchmarks only.

photon_engine (the NumPy MCML photon engine, pluggable tallies), monte_carlo
(``mc_layers``, ``mc_slab``: its MCML front end), mc_paths (``mc_detected_paths``,
``reweight_detected``: its detector-ring front end with per-layer paths),
adding_doubling (``slab_rt``, iadpython) and lut_checks (the look-up table against
direct solves). None of them is on the simulator's path.
"""
