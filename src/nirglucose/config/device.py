"""The device capabilities a wearable team chooses (``device.*``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from ._base import _Model

#: Pulse-oximeter accuracy: FDA premarket guidance ("Pulse Oximeters - Premarket
#: Notification Submissions", 2013) asks for A_rms <= 3.0 % SpO2 over 70-100 % for
#: transmittance sensors (3.5 % for reflectance); ISO 80601-2-61:2017 requires <= 4 %. [%]
SPO2_ARMS_PCT = 3.0


class DeviceConfig(_Model):
    """Hardware capabilities a wearable team chooses; all off is a basic four-LED wearable.

    Each switch is a design choice with a cost (an extra photodiode, a spring-loaded
    probe, a clinical-grade physiological workup, a PPG front end); :data:`PRESETS`
    record which ones a preset assumes (:data:`PRESET_CAPABILITIES`).
    """

    monitor_photodiode: bool = Field(
        False,
        description="A monitor photodiode reads each LED's output at every reading (through "
        "the reference path's attenuation, hardware.reference_transmission), so adc_ref_<nm> "
        "is a per-reading monitor code instead of the start-up reference: cancels LED power "
        "drift, ageing and flicker, not the thermal wavelength shift; the monitor has its own "
        "shot and Johnson noise and its own ADC conversion. [-]",
    )
    constant_force_probe: bool = Field(
        False,
        description="A constant-force (spring-loaded) probe: contact pressure is held at the "
        "cohort's mean (0.5 of full scale), so readings carry no pressure-driven coupling, "
        "blanching or compression variation. [-]",
    )
    physiology: Literal["measured", "exact"] = Field(
        "measured",
        description="'measured': the physiological vector carries the instruments' errors "
        "(measurement.*); 'exact': it equals the truth (a clinical-grade workup; also makes "
        "blood_volume_pct and spo2_pct exact). [-]",
    )
    ppg_perfusion_spo2: bool = Field(
        False,
        description="Perfusion and oxygen saturation measured from the pulsatile PPG the "
        "wearable records: adds the columns blood_volume_pct (detected dermal blood volume "
        "fraction) and spo2_pct (the dermal saturation the optics see), with the errors "
        "device.blood_volume_error_rel and device.spo2_error_pct. [-]",
    )
    reading_times: bool = Field(
        False,
        description="The device records when each reading is taken: a time_min column, "
        "minutes since the subject's start-up reference (hardware.hours_since_reference_h), "
        "as a worn device's file has one; the LEDs have aged by that time "
        "(hardware.led_ageing_per_1000h, or an LED's own ageing_per_1000h). A device's twin "
        "sets it for a file with reading times (nirglucose.twin). [-]",
    )
    humidity_compensation: bool = Field(
        False,
        description="Firmware divides each reading by the coupling-loss-vs-humidity curve "
        "(environment.humidity_coupling_loss, factory-calibrated) at the RH sensor's reading "
        "(humidity_pct): only the curve at the sensor's error remains. [-]",
    )
    spo2_error_pct: float = Field(
        SPO2_ARMS_PCT,
        ge=0, le=50, description="SD of spo2_pct: pulse-oximeter A_rms (FDA 2013 guidance: <= 3 % "
        "transmittance, 3.5 % reflectance; ISO 80601-2-61: <= 4 %). "
        "At most 50 %, half of SpO2's scale. [%]",
    )
    blood_volume_error_rel: float = Field(
        0.1,
        ge=0,
        le=1,
        description="Relative SD of blood_volume_pct (an assumption of this package: no "
        "standard governs a PPG blood-volume estimate). [-]",
    )
