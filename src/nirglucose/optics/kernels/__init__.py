"""Compiled (numba) kernels of the optics, each beside nothing but itself.

mc_white (the white Monte Carlo of three-layer skin behind the ``rte-lut`` table),
lut_kernel (the table's interpolation on the simulator's fast path) and band_kernel
(band-integrated layer optics and detected fraction, one pass per slice). Each is
imported lazily by its caller, so ``import nirglucose`` does not import numba.
"""
