"""Compiled (numba) kernels of the simulation, each an implementation detail of one
NumPy module that stays the documented reference (and a test holds the two equal).

uva_padova_rk4 (the fixed-step RK4 of :func:`nirglucose.simulation.uva_padova.integrate`,
bit for bit). Imported lazily by its caller, so ``import nirglucose`` does not import
numba.
"""
