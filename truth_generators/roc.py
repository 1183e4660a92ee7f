"""Plug-ins of the inspection ROC study (``truth_generator: "truth_generators.roc:<function>"``): each
car's bump crossing from a simulator that is not the product's model.

- :func:`bump_crossing`: the independent simulator (:mod:`.independent_sim`) as it is, the car's drawn
  values replacing its defaults (``config/studies/inspection_roc_independent.yaml``);
- :func:`family_bump_crossing`: a form of the truth-generator family (:mod:`.family`), by default the
  held-out forms of ``family_split.yaml`` cycled over the cars (``config/studies/inspection_roc_held_out.yaml``).

The study calls ``plugin(draw, roc)`` with the car's draw (``car``, ``values`` of the varied vehicle-file
fields, ``speed_kmh``, ``bump_height`` in m, ``gyro_noise_deg_s``, ``oil``, ``noise_seed``) and the
study's normalised ``roc`` section, and takes ``(drive, k_after, pitch_rate_deg_s)``: the drive, the IMU
sample index once both axles have left the bump, and the measured pitch rate in deg/s. A plug-in's drive
may name its truth form in ``metadata["truth_form"]`` (the study records it in ``cars.csv``). A plug-in
``f`` may come with ``f_options(options, roc) -> dict`` in its module: it checks the study's
``roc.truth_generator_options`` when the study is loaded (ValueError: refused) and returns them
normalised, as the plug-in then reads them from ``roc["truth_generator_options"]``.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import fields, replace

import numpy as np

from . import independent_sim as ind

#: vehicle-file fields -> the independent simulator's car (TruthCar) and friction (TruthFriction) fields
TRUTH_CAR = {"sprung_mass": "sprung_mass", "unsprung_mass": "unsprung_mass", "cg_height": "cg_height",
             "roll_inertia": "roll_inertia", "pitch_inertia": "pitch_inertia", "tyre_stiffness": "tyre_stiffness",
             "wheel_rate": "wheel_rate", "arb_rate": "arb_rate"}
TRUTH_FRICTION = {"axle_friction": "axle_level", "damper_friction_intact": "damper_intact",
                  "damper_friction_empty": "damper_empty"}
#: the family's bump-crossing sensor (``family.bump_crossing``): IMU rate [Hz], accelerometer noise [m/s^2]
FAMILY_IMU_RATE_HZ, FAMILY_ACCEL_NOISE = 200.0, 0.02


def _after_bump(drive, man: ind.TruthManeuver, wheelbase: float) -> int:
    """Index of the first IMU sample once the rear axle has left the bump."""
    t = (drive.imu.t_ns - drive.imu.t_ns[0]) * 1e-9
    return int(np.searchsorted(t, man.lead_in_s + (man.bump_length_m + wheelbase) / man.speed_mps))


def bump_crossing(draw: Mapping, roc: Mapping):
    """The car's bump crossing from the independent simulator, the car's drawn values replacing its
    defaults; same outputs as ``susp_sim_ros.analysis.inspection.roc.bump_drive``."""
    car_kw = {TRUTH_CAR[f]: v for f, v in draw["values"].items() if f in TRUTH_CAR}
    fr_kw = {TRUTH_FRICTION[f]: v for f, v in draw["values"].items() if f in TRUTH_FRICTION}
    car = ind.TruthCar(**car_kw)
    man = ind.TruthManeuver.bump(speed_kmh=draw["speed_kmh"], height_m=draw["bump_height"], wheelbase_m=car.wheelbase)
    sensor = ind.TruthSensor(imu_rate_hz=roc["imu_rate_hz"], gyro_noise_deg_s=(draw["gyro_noise_deg_s"],) * 3,
                             accel_noise_m_s2=(roc["accel_noise_m_s2"],) * 3, exact_rms=False)
    drive = ind.make_drive(car, ind.TruthFriction(**fr_kw), None, man, sensor, draw["oil"], seed=draw["noise_seed"])
    return drive, _after_bump(drive, man, car.wheelbase), np.degrees(drive.imu.gyro[:, 1])


# ---- the truth-generator family ---------------------------------------------------------------------------
def family_bump_crossing_options(options: Mapping | None, roc: Mapping) -> dict:
    """The options of :func:`family_bump_crossing`, checked and normalised when the study is loaded:
    ``forms``, a non-empty list of the family's form names (default: every form of the held-out split of
    ``family_split.yaml`` as it is when the study is loaded, in registry order; the list enters the
    study's hash, so a form added later is a new study, never mixed into a resumed one). The study's
    sensor must be the family's (200 Hz IMU, 0.02 m/s^2 accelerometer noise)."""
    from . import family
    options = dict(options or {})
    unknown = set(options) - {"forms"}
    if unknown:
        raise ValueError(f"unknown option(s) {', '.join(sorted(unknown))}; known: forms")
    names = options.get("forms")
    if names is None:
        names = [f.name for f in family.forms("held_out")]
    if (not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names)
            or len(set(names)) != len(names)):
        raise ValueError(f"forms: expected a non-empty list of distinct form names, got {names!r}")
    missing = [n for n in names if n not in family.FORMS]
    if missing:
        raise ValueError(f"forms: not forms of truth_generators/family.py: {', '.join(missing)}")
    if (not math.isclose(float(roc["imu_rate_hz"]), FAMILY_IMU_RATE_HZ)
            or not math.isclose(float(roc["accel_noise_m_s2"]), FAMILY_ACCEL_NOISE)):
        raise ValueError(f"the family's bump crossing has a {FAMILY_IMU_RATE_HZ:g} Hz IMU with {FAMILY_ACCEL_NOISE:g} "
                         f"m/s^2 accelerometer noise; set roc.imu_rate_hz and roc.accel_noise_m_s2 to them")
    return {"forms": list(names)}


def family_form_of(draw: Mapping, forms: list[str]) -> str:
    """The form of car ``draw["car"]``: the configured forms cycled over the cars (car i: form i mod n),
    so every form gets every n-th car and the oil states fall on the forms at random."""
    return forms[int(draw["car"]) % len(forms)]


def family_car(form, draw: Mapping, seed: int) -> ind.TruthCar:
    """The car of ``form`` for this draw: the form's car (its ``car_changes``; a ``car_band`` drawn with
    ``seed``) with the car's drawn values in place of the form's, except for a form whose car is beyond
    the priors (band ``beyond``): that car is the form's point, so its values stay."""
    car = form.car(seed)
    if form.car_band == "beyond":
        return car
    return replace(car, **{TRUTH_CAR[f]: v for f, v in draw["values"].items() if f in TRUTH_CAR})


def family_bump_crossing(draw: Mapping, roc: Mapping):
    """The car's bump crossing from a form of the truth-generator family (:func:`family_form_of` of the
    study's ``truth_generator_options.forms``): the form's structure (integrator and step, friction forms,
    damper-curve shape, oil law, hidden physics) on :func:`family_car`, the drawn friction levels in the
    form's friction, through ``family.bump_crossing`` (its sensor: a random gyro bias N(0, 0.02) deg/s per
    axis on top of the study's noise) seeded with the car's ``noise_seed``. Same outputs as
    :func:`bump_crossing`; ``metadata["truth_form"]`` names the form."""
    from . import family
    opts = roc.get("truth_generator_options") or family_bump_crossing_options(None, roc)
    form = family.FORMS[family_form_of(draw, list(opts["forms"]))]
    seed = int(draw["noise_seed"])
    car = family_car(form, draw, seed)
    friction = replace(form.friction, **{TRUTH_FRICTION[f]: v for f, v in draw["values"].items()
                                         if f in TRUTH_FRICTION})
    # the car as the form's car_changes on the nominal band: family.bump_crossing then builds exactly it
    as_built = replace(form, car_band="nominal", friction=friction,
                       car_changes={f.name: getattr(car, f.name) for f in fields(car)})
    drive = family.bump_crossing(as_built, seed, draw["oil"], draw["speed_kmh"], draw["bump_height"],
                                 gyro_noise_deg_s=draw["gyro_noise_deg_s"])
    drive.metadata["truth_form"] = form.name
    assert drive.imu is not None
    man = ind.TruthManeuver.bump(speed_kmh=draw["speed_kmh"], height_m=draw["bump_height"], wheelbase_m=car.wheelbase)
    return drive, _after_bump(drive, man, car.wheelbase), np.degrees(drive.imu.gyro[:, 1])
