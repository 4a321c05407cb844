"""
Simulate a dataset and look at its codes
========================================

:func:`nirglucose.simulate` draws a cohort on a preset and returns a
:class:`nirglucose.Dataset`: one row per snapshot, the ADC codes of each LED
(``adc_<nm>``), the device's reference codes (``adc_ref_<nm>``), the measured
physiological vector and, for analysis only, the ``true_*`` columns.
"""

import matplotlib.pyplot as plt
import numpy as np

import nirglucose as ng

ds = ng.simulate(preset="paper", n_subjects=20, per_subject=3, seed=0)
frame = ds.frame
print(ds)
print(frame.shape, "rows x columns")

# %%
# Absorbance per LED, A = log10(I0 / I), with I0 the reference code: one line per
# snapshot of the first four subjects. The spread between subjects (melanin, skin
# thickness, blood) is far larger than what glucose changes.
nms = sorted(int(c.removeprefix("adc_")) for c in frame if c[4:].isdigit())
absorbance = np.log10(
    frame[[f"adc_ref_{nm}" for nm in nms]].to_numpy()
    / frame[[f"adc_{nm}" for nm in nms]].to_numpy()
)
fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(9, 3.5), layout="constrained")
for row in np.flatnonzero(frame["subject_id"].to_numpy() < 4):
    ax0.plot(nms, absorbance[row], marker="o", color=f"C{frame['subject_id'].iat[row]}")
ax0.set(xlabel="LED wavelength [nm]", ylabel="absorbance A [-]",
        title="one line per snapshot, colour = subject")

# %%
# The raw code of the 1150 nm channel against the reference glucose: the weak
# correlation the estimators have to work with.
ax1.scatter(frame["glucose_mgdl"], frame["adc_1150"], s=10)
ax1.set(xlabel="reference glucose [mg/dL]", ylabel="ADC code, 1150 nm [-]",
        title=f"r = {np.corrcoef(frame['glucose_mgdl'], frame['adc_1150'])[0, 1]:.2f}")
plt.show()
