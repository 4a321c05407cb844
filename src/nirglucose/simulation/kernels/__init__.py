"""Compiled (numba) kernels of the simulation, implementation details only.

contact_kernel (the contact layer after its draws in one pass), glucose_kernel (the
glucose layer's snapshots in one pass), hardware_kernel (the hardware
layer's element-wise chain, LED power to ADC code, in one pass), measurement_kernel (each
measured column, the PPG front end, in one pass), physiology_kernel (the
physiology layer's per-reading state in one pass), random_kernel (the truncated normal in
one pass, its normal CDF and inverse SciPy's bit for bit; the categorical draw's
look-up) and uva_padova_rk4
(the fixed-step RK4 of :func:`nirglucose.simulation.uva_padova.integrate`).
The physics, units and citations live in the NumPy functions of
:mod:`nirglucose.simulation.contact`, :mod:`nirglucose.simulation.glucose`,
:mod:`nirglucose.simulation.hardware`, :mod:`nirglucose.simulation.measurement`,
:mod:`nirglucose.simulation.physiology`, :mod:`nirglucose.simulation._random` and
:mod:`nirglucose.simulation.uva_padova`, which stay the reference: a test holds each
kernel equal to them bit for bit. Imported lazily by their callers (they import numba),
so ``import nirglucose`` does not import numba.
"""
