"""
A three-LED, 10-bit device
==========================

The LED set and the ADC are configuration: one record per LED under ``leds`` and
``hardware.adc_bits``. Every model fits and predicts on whatever columns the device
records, and remembers the device it was fitted on (``model.schema_``).
"""

import matplotlib.pyplot as plt

import nirglucose as ng
from nirglucose.metrics import rmse
from nirglucose.models import make_model

led = {"fwhm_nm": 40, "power_mw": 3, "responsivity_a_per_w": 0.5}
three = {"leds": [{"wavelength_nm": w, **led} for w in (850, 940, 1150)],
         "hardware.adc_bits": 10}
ds = ng.simulate(preset="paper", n_subjects=30, per_subject=3, seed=0, overrides=three)
frame = ds.frame
print(sorted(c for c in frame if c.startswith("adc_")))

# Dataset.rows keeps the device description (10 bits) that a bare DataFrame would lose
in_train = (frame["subject_id"] < 20).to_numpy()
train, test = ds.rows(in_train), ds.rows(~in_train)
model = make_model("ebl").fit(train)
print(model.schema_.describe())
print(f"EBL on the 3-LED device: RMSE {rmse(test.frame['glucose_mgdl'], model.predict(test)):.1f} mg/dL")

# %%
# Codes of a 10-bit ADC run from 0 to 1023.
fig, ax = plt.subplots(figsize=(5, 3.5), layout="constrained")
for nm in (850, 940, 1150):
    ax.hist(frame[f"adc_{nm}"], bins=20, alpha=0.6, label=f"{nm} nm")
ax.set(xlabel="ADC code [-]", ylabel="snapshots", xlim=(0, 1023))
ax.legend()
plt.show()
