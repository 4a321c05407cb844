"""Validation references: solvers and checks that serve the tests, the speed benchmarks
and the research studies only (formerly ``nirglucose.optics.reference``).

photon_engine (the NumPy MCML photon engine, pluggable tallies), monte_carlo
(``mc_layers``, ``mc_slab``: its MCML front end), mc_paths (``mc_detected_paths``,
``reweight_detected``: its detector-ring front end with per-layer paths),
adding_doubling (``slab_rt``, iadpython) and lut_checks (the look-up table against
direct solves). None of them is on the simulator's path, so none ships in the
installed package: this folder lies outside ``src/`` (the wheel's only source), and
``tests`` (pytest's ``pythonpath``), ``benchmarks/`` and ``studies/`` put it on
``sys.path``. It reads a few of the optics' own helpers (``nirglucose.optics._inputs``,
``nirglucose.optics.lut.build._mc_run_kwargs``) to run exactly the package's settings.
"""
