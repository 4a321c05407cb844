"""Compiled (numba) kernels of the simulator's layers, implementation details only.

hardware_kernel (the hardware layer's element-wise chain, LED power to ADC code, in one
pass) and random_kernel (the truncated normal's passes around the inverse normal CDF).
The physics, units and citations live in the NumPy functions of
:mod:`nirglucose.simulation.hardware` and :mod:`nirglucose.simulation._random`, which stay
the reference: a test holds each kernel equal to them bit for bit. Imported lazily by
their callers (they import numba).
"""
