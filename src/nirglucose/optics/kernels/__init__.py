"""Compiled (numba) kernels of the optics, each beside nothing but itself.

mc_white (the white Monte Carlo of three-layer skin behind the ``rte-lut`` table),
lut_kernel (the table's interpolation on the simulator's fast path) and band_kernel
(band-integrated layer optics and detected fraction, one pass per slice). lut_kernel and
band_kernel are imported lazily by their callers; mc_white is imported at module level by
:mod:`~nirglucose.optics.lut.grid`, :mod:`~nirglucose.optics.lut.build` and
``nirglucose_reference.lut_checks``, so importing
:mod:`nirglucose.optics.lut` imports numba. ``import nirglucose`` alone does not.
"""
