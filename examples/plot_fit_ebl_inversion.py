"""
Fit two estimators and compare their predictions
================================================

Fit the Enhanced Beer–Lambert model (``ebl``: ridge on 56 physics features) and the
deployable forward-model inversion (``device-inversion``: the device's parts over the
published optics tables, glucose's response learned from the training rows) on the same
subjects, and predict subjects neither has seen. Splits are by subject. Both read only
the measured columns of a plain table, as they would a device's file
(``physics-inversion``, a reference that reads the generating scenario, refuses one).
"""

import matplotlib.pyplot as plt

import nirglucose as ng
from nirglucose.metrics import mard, rmse
from nirglucose.models import make_model

frame = ng.simulate(preset="paper", n_subjects=40, per_subject=3, seed=1).frame
train = frame[frame["subject_id"] < 30]
test = frame[frame["subject_id"] >= 30]
ref = test["glucose_mgdl"].to_numpy()

predictions = {}
for name in ("ebl", "device-inversion"):
    model = make_model(name).fit(train)  # measured columns only, never true_*
    predictions[name] = model.predict(test)  # [mg/dL]
    print(f"{name:>18}: RMSE {rmse(ref, predictions[name]):5.1f} mg/dL, "
          f"MARD {mard(ref, predictions[name]):5.1f} %")

# %%
# Predicted against reference glucose on the held-out subjects; the diagonal is a
# perfect estimate. Ten test subjects cannot rank two models: ``nirglucose benchmark``
# repeats the split and reports confidence intervals.
fig, ax = plt.subplots(figsize=(4.5, 4.5), layout="constrained")
for name, pred in predictions.items():
    ax.scatter(ref, pred, s=14, label=name)
lims = [min(ref.min(), 40), max(ref.max(), 400)]
ax.plot(lims, lims, color="0.5", lw=1)
ax.set(xlabel="reference [mg/dL]", ylabel="predicted [mg/dL]", xlim=lims, ylim=lims)
ax.legend()
plt.show()
