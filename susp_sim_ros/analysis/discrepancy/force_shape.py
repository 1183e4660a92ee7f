"""Physics read off the shape of the missing force (issue 26, items 3-4).

What the model still lacks is regressed on features of the model's own corner states
(:data:`~susp_sim_ros.model.learned_force.FEATURES`: deflection and its cube, deflection velocity, its
square and a knee in it, friction-like states, stroke amplitude, wheel forces, the left-right
deflection difference and a free play of it, a spring that relaxes, springs met beyond a contact gap of bump
or rebound, friction growing with the compression, and where ``library.position_damping`` is set a damping
met beyond such a gap, where ``library.zone_damping`` is one met beyond it on either side of static), one
coefficient [N] per (feature, axle). The regression
runs through the model's own dynamics: each column is the effect of a feature's force, acting at the
axle's two corners as a suspension force does, on every compared signal of every drive (the
forward-difference Jacobian of the whitened residual, as the finder's criteria see it), and the target
is the residual itself, of the model as fitted so far with its calibration at the vehicle file's values:
calibration and learned physics then compete on equal terms in the joint fit that follows, instead of
the calibration having taken up first what the physics would explain. When nothing is stable there, a
second look reads the residual with the calibration as fitted, every value that moved more than one prior
sd set back to its prior (the finder's ``_without_far_shifts``): the values within their priors are the
car, whose differences from the vehicle file can hide a force at the file's values; a far shift is a
hypothesis that may have taken up the physics (a blown-off valve read as weaker dampers).
That is the missing force attributed to dependences without first estimating it as a smoothed series
(:mod:`.missing_force`, the picture an engineer reads), whose body-mode band and uncertainty blur the fast
forces of a bump impact.

Selection is sparse and held out by drive: forward stepwise selection in which every step adds the
column that, fitted with those chosen before, best predicts the drives left out one at a time, with the
number of dependences, none included, chosen on the same left-out drives by the one-standard-error rule
(:func:`_forward_cv`), all from each drive's sufficient statistics, repeated on drive-bootstrap resamples;
a dependence is *stable* when it is selected in most resamples that can test it (stability selection,
Meinshausen and Buehlmann 2010; :func:`select`), and so is a law family (:data:`LAW_OF`: the spring forms
of one axle, its damping forms, ...) whose members split the resamples' votes, none of them stable on
its own, through the member chosen most often (cluster stability selection, Faletto and Bien 2022).
Until 2026-11-28 the step was orthogonal matching
pursuit's (scikit-learn's ``orthogonal_mp_gram``), which adds the column most correlated with the target
on all drives: it split the votes of correlated dependences (a plain friction level against one growing
with the amplitude) and named neither (benchmarks/RESULTS.md, 2026-11-28). Why not PySINDy: it regresses
measured state derivatives on a library; here the library's columns are simulated effects.

The stable set is then a learned physics term (:data:`~susp_sim_ros.model.learned_force.LEARNED_FORCE`,
TERM ``unlisted_force``) with one coefficient per dependence (and the knee or free play it selected,
freed), which the finder fits and tests like every listed candidate (criterion, decoys, held-out
drives, recalibration) and which competes with them on the criterion. When listed terms stand for
every stable dependence (:data:`LISTED_FOR`), the learned term is not offered: those listed terms are
in the competition already (``listed_rivals`` in the record). Limits: the dependences and the offered
knee or free play are selected on all drives, so the held-out test refits the learned term's values, not
its choice of dependences; one knee, one free play and one contact gap serve both axles (and one contact
gap both senses). Where ``fit.extend_learned`` is set, a named learned term may grow at a later step by the
stable dependences the regression of the residual it leaves adds (:func:`extended`; its shapes held there).

Input features (issue 26, item 5): beside the state features, the regression offers forces that follow
an input and no state (:data:`~susp_sim_ros.model.input_force.INPUT_FEATURES`: the road height under
each wheel and its rate, the wheel's rotation angle ``path / rolling radius`` as sine and cosine of
harmonics 1 and 2), their columns the simulated effect of the term
:data:`~susp_sim_ros.model.input_force.INPUT_FORCE` as every other column's. They compete in the same
selection under the same stability rules, but they are never physics: a stable set led by an input
feature (:attr:`Selection.input_led`) is an input the recording lacks (the finder's ``unmeasured_input``,
its ``kind`` from :data:`~susp_sim_ros.model.input_force.INPUT_KIND`), and stable input features beside
leading state ones are left out of the learned term (:meth:`Selection.physics`).
"""
from __future__ import annotations

import math
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from itertools import combinations_with_replacement

import numpy as np

from ...model.input_force import INPUT_FEATURES, INPUT_FORCE, INPUT_KIND
from ...model.learned_force import CONTACT_SQUARES, DAMPER_OIL, FEATURES, FRICTION_LIKE, LAW_SHAPE_FEATURES, \
    LEARNED_FORCE, LEVEL_GROWTH, PRESLIDING, REBOUND_RATIO, STRIBECK_VELOCITY, WEAKENING, CREEP, CREEP_VELOCITY, \
    shape_defaults
from ...model.layout import P_INDEX
from ...model.params import AXLE_CORNERS, CORNER_NAMES, load_settings
from .candidates import PHYSICS, CandParam, Candidate, axle_map
from .fit import debias, fd_jacobian

TERM = LEARNED_FORCE.name
INPUT_TERM = INPUT_FORCE.name  # the input features' term: columns of the regression, never a candidate
AXLES = tuple(AXLE_CORNERS)  # ("front", "rear")
#: the listed TERM that stands for a dependence (None: none does)
LISTED_FOR = {"constant": "damper_gas_preload", "deflection": "damper_gas_preload",
              "deflection_velocity": "extra_viscous_damping", "peak_deflection": "friction_amplitude",
              "lateral_force": "friction_lateral_force", "longitudinal_force": "friction_longitudinal_force"}
#: plain words per dependence (the description's parts)
WORDS = {"constant": "a constant force offset", "deflection": "spring-like (grows with the deflection)",
         "deflection_cubed": "a progressive spring (grows with the cube of the deflection)",
         "deflection_velocity": "viscous (grows with the deflection velocity)",
         "velocity_squared": "grows with the square of the deflection velocity, as far as the damper holds "
                             "oil (orifice-like)",
         "velocity_beyond_knee": "changes slope above a deflection velocity of {knee:.2f} m/s, as far as the damper "
                                 "holds oil (a damper valve opening or at its stop)",
         "sign_velocity": "friction-like (a jump when the deflection reverses)",
         "peak_deflection": "friction-like, growing with the remembered peak deflection",
         "lateral_force": "friction-like, growing with the lateral wheel force",
         "longitudinal_force": "friction-like, growing with the longitudinal wheel force",
         "roll_deflection": "acts on the left-right deflection difference (anti-roll-bar-like)",
         "roll_free_play": "acts only within +-{gap_mm:.1f} mm of left-right deflection difference "
                           "(free play in the anti-roll bar)",
         "relaxing_deflection": "a spring that relaxes in {tau:.2f} s, stiffer the faster the deflection changes "
                                "(viscoelastic: a rubber bushing or mount)",
         "bump_contact": "a spring met beyond {gap_mm:.0f} mm of bump (a jounce bumper, coils coming to block; "
                         "at 0 mm a spring stiffer in bump than in rebound)",
         "rebound_contact": "a spring met beyond {gap_mm:.0f} mm of rebound (a rebound or top-out spring)",
         "compression": "friction-like, growing with the compression and falling in rebound (a strut's guide or "
                        "seal pressed harder as the spring or the damper's gas is compressed)",
         "creep_damping": "creeps at low sliding velocity (viscous below a creep velocity, fading above)",
         "bump_damping": "a damping met beyond {gap_mm:.0f} mm of bump, growing with the depth, as far as the damper "
                         "holds oil (a hydraulic compression stop, a position-sensitive damper)",
         "rebound_damping": "a damping met beyond {gap_mm:.0f} mm of rebound, growing with the depth, as far as the "
                            "damper holds oil (a hydraulic rebound stop, a position-sensitive damper)",
         "zone_damping": "a damping met beyond {gap_mm:.0f} mm of bump and {rgap_mm:.0f} mm of rebound, growing with "
                         "the depth, as far as the damper holds oil (a position-sensitive damper: a soft zone around "
                         "static)",
         "deflection_squared": "a spring whose rate grows through the whole stroke, its force of one sense in bump "
                               "and rebound (a gas charge's or air spring's law beyond its static rate, a "
                               "rising-rate linkage)",
         "road_height": "follows the road height under the wheel (an input, not a state)",
         "road_rate": "follows the rate of the road height under the wheel (an input, not a state)",
         **{f"rotation_{t}{k}": f"follows the wheel's rotation, harmonic {k}, {part} part (an input, not a state)"
            for t, part in (("sin", "sine"), ("cos", "cosine")) for k in (1, 2)}}


#: a zone whose one end (``far``: rebound or bump) lies beyond the drives' reach (:func:`drives_reach`) is, as far as
#: the drives tell, a damping met beyond its other end (``near``) only: a stop (Dixon, The Shock Absorber Handbook,
#: 2007, ch. 9 on hydraulic stops)
ZONE_ONE_END = ("a damping met beyond {near_mm:.0f} mm of {near}, growing with the depth, as far as the damper holds "
                "oil; its {far} end, {far_mm:.1f} mm, lies beyond the deepest {far} the drives reach with oil in the "
                "damper ({reach_mm:.1f} mm), so as far as these drives tell it is a stop in {near} (a hydraulic "
                "{stage} stop, a position-sensitive damper's {near} end); a drive deeper in {far} tells whether a soft "
                "zone ends there")
#: the damper stage a stop on each side of static acts in
STOP_STAGE = {"bump": "compression", "rebound": "rebound"}

#: the dampings of the vocabulary: the damping law family's members (:data:`LAW_OF`)
DAMPINGS = ("deflection_velocity", "velocity_squared", "velocity_beyond_knee", "bump_damping", "rebound_damping",
            "zone_damping")
#: what a positive and a negative coefficient of a dependence mean (the force is positive up on the body)
SENSE = {"constant": ("pushes the body up", "pulls the body down"),
         "deflection_squared": ("stiffer in bump, softer in rebound", "softer in bump, stiffer in rebound"),
         **{f: ("stiffer", "softer") for f in ("deflection", "deflection_cubed", "roll_deflection", "roll_free_play",
                                                "relaxing_deflection", "bump_contact", "rebound_contact")},
         **{f: ("more damping", "less damping") for f in DAMPINGS},
         **{f: ("more friction", "less friction") for f in FRICTION_LIKE},
         **{f: ("positive", "negative") for f in INPUT_FEATURES}}


#: features that are one dependence together: the sine and cosine of a rotation harmonic (their ratio is the
#: wheel's unknown phase, so a resample may pick either); selected, counted and kept as a pair
GROUP_OF = {f"rotation_{t}{k}": f"rotation_{k}" for t in ("sin", "cos") for k in (1, 2)}


#: the law family of a dependence (cluster stability selection, Faletto and Bien 2022, arXiv:2201.00494): the
#: features of one kind of law of one corner state, whose simulated effects correlate over a bump crossing and
#: a sine steer, so the resamples may split their votes between the members (a progressive spring read as
#: a cubic in some, a spring stiffer in rebound than in bump in others); a family selected in most resamples
#: is a stable dependence of its kind although no single member is (:func:`select`). Features not listed are
#: a family of their own (the relaxing spring, both spring and damper; the constant; the inputs).
LAW_OF = {**{f: "spring" for f in ("deflection", "deflection_cubed", "bump_contact", "rebound_contact",
                                    "deflection_squared")},
          **{f: "damping" for f in DAMPINGS},
          **{f: "friction" for f in FRICTION_LIKE},
          **{f: "roll" for f in ("roll_deflection", "roll_free_play")}}
#: the law families themselves; any other feature is a family of its own, stable or not as itself
LAW_FAMILIES = frozenset(LAW_OF.values())

#: springs met beyond a gap of bump or rebound, and a spring law's smooth progressive part (:func:`spring_law`)
CONTACTS = ("bump_contact", "rebound_contact")
PROGRESSIVE = "deflection_cubed"
#: the forms of a spring law's progressive part (:func:`spring_law`): the cube of the deflection, or the square of
#: each stable contact's depth beyond its gap (``fit.contact_square_competes``)
CUBE, CONTACT_SQUARE = "cube", "contact_square"
#: the bump deflection [m] at which the words give a progressive part's force: a bump crossing's (30-60 mm)
WORDS_DEFLECTION_M = 0.04


def group_of(feature: str) -> str:
    """The dependence a feature belongs to for stability: the feature itself, or its pair (:data:`GROUP_OF`)."""
    return GROUP_OF.get(feature, feature)


def group_key(key: tuple[str, str]) -> tuple[str, str]:
    """:func:`group_of` a (feature, axle) key, with its axle."""
    return group_of(key[0]), key[1]


def law_key(key: tuple[str, str]) -> tuple[str, str]:
    """The law family (:data:`LAW_OF`) of a (feature, axle) key, with its axle."""
    g = group_of(key[0])
    return LAW_OF.get(g, g), key[1]


#: the shape parameter of the features that have one
_SHAPE_OF = {"velocity_beyond_knee": "knee_velocity", "roll_free_play": "free_play",
             "relaxing_deflection": "relaxation_time", "bump_contact": "contact_gap", "rebound_contact": "contact_gap",
             "bump_damping": "contact_gap", "rebound_damping": "contact_gap", "zone_damping": "contact_gap"}
#: the gap of the features met in rebound, where the fit holds it apart from the contact gap (``fit.rebound_gap``)
REBOUND_GAP = "rebound_gap"
#: the features met beyond the rebound gap (a zone's rebound side too: :func:`shapes_of`)
REBOUND_GAPPED = ("rebound_contact", "rebound_damping")
#: the shapes a learned term holds one value of (for every feature that has it): held at their fitted values when
#: the term is extended (:func:`extended`)
HELD_SHAPES = frozenset(_SHAPE_OF.values()) | {REBOUND_GAP}
#: the config entry of each such shape parameter's range in the learned term's fit
_SHAPE_RANGE = {"knee_velocity": "fit.knee_velocity_range_m_s", "free_play": "fit.free_play_range_m",
                "relaxation_time": "fit.relaxation_time_range_s", "contact_gap": "fit.contact_gap_range_m",
                REBOUND_GAP: "fit.contact_gap_range_m"}
#: the config entry of the values each such feature is offered at in the regression
_SHAPE_VALUES = {"velocity_beyond_knee": "library.knee_velocities_m_s", "roll_free_play": "library.free_plays_m",
                 "relaxing_deflection": "library.relaxation_times_s", "bump_contact": "library.contact_gaps_m",
                 "rebound_contact": "library.contact_gaps_m", "bump_damping": "library.contact_gaps_m",
                 "rebound_damping": "library.contact_gaps_m", "zone_damping": "library.contact_gaps_m"}
#: a damping met beyond a contact gap: offered to the regression only where ``library.position_damping`` is set
POSITION_DAMPING = ("bump_damping", "rebound_damping")
#: a damping met beyond a gap on either side of static (one coefficient for a soft zone's two ends): offered only
#: where ``library.zone_damping`` is set
ZONE_DAMPING = "zone_damping"
#: the forces met beyond a gap, by the side of static their gap lies on (a zone's on both): how deep beyond it the
#: drives reach is said with them (:func:`_reach_words`)
GAP_SIDES = {"bump_contact": "bump", "bump_damping": "bump", "rebound_contact": "rebound",
             "rebound_damping": "rebound", ZONE_DAMPING: "both"}
#: a spring of one sense in bump and rebound: offered only where ``library.deflection_squared`` is set
EVEN_SPRING = "deflection_squared"
#: the spring features a smooth progressive part (:data:`PROGRESSIVE`) is fitted beside (:func:`spring_law`) and
#: named with (:meth:`Selection.description`)
SMOOTH_LAW_SPRINGS = (*CONTACTS, EVEN_SPRING)


def learned_in(variant) -> bool:
    """Whether ``variant`` (a FrictionVariant) already has a learned term (one the finder wrote)."""
    return any(s.term.name == TERM for s in variant.terms)


def settings(path=None) -> dict:
    """``config/force_shape.yaml`` as ``{"section.key": value}``."""
    return load_settings("force_shape.yaml", path)


def shape_of(feature: str, cfg: dict) -> str | None:
    """The shape parameter a feature is offered and fitted at: its own (:data:`_SHAPE_OF`), the rebound gap for a
    feature met in rebound where ``fit.rebound_gap`` holds the two gaps apart; None for a feature without one."""
    if feature in REBOUND_GAPPED and bool(cfg["fit.rebound_gap"]):
        return REBOUND_GAP
    return _SHAPE_OF.get(feature)


def _slots(name: str | None, cfg: dict, zone: bool = False) -> tuple[str, ...]:
    """The learned term's parameters a value of shape ``name`` is written to: the contact gap to the rebound gap
    too unless ``fit.rebound_gap`` holds them apart (one gap for both senses, as the term had before it had two),
    and a ``zone``'s one gap to both where it does (a column offers a zone centred on static; the fit then moves
    its ends apart)."""
    if name == "contact_gap" and (zone or not bool(cfg["fit.rebound_gap"])):
        return name, REBOUND_GAP
    return () if name is None else (name,)


def shapes_of(feature: str, cfg: dict) -> tuple[str, ...]:
    """The learned term's parameters a value of the shape of ``feature`` (:func:`shape_of`) is written to
    (:func:`_slots`)."""
    return _slots(shape_of(feature, cfg), cfg, feature == ZONE_DAMPING)


@dataclass(frozen=True)
class Column:
    """One regression column: a feature on one axle at one shape value (knee or free play, else None)."""

    feature: str
    axle: str
    shape: float | None = None

    @property
    def key(self) -> tuple[str, str]:
        return self.feature, self.axle

    @property
    def coefficient(self) -> str:
        """The name of its coefficient in the learned candidate."""
        return f"{self.feature}_{self.axle}"


def library(cfg: dict, shapes: dict | None = None) -> list[tuple[str, float | None]]:
    """(feature, shape value) of every library entry: the features with a shape value (knee, free play,
    relaxation time, contact gap) once per offered value, or once at the value ``shapes`` holds for it
    (``{shape: value}``, a learned term's as fitted: :func:`extended`), the others once (a damping beyond a
    contact gap only where ``library.position_damping`` is set, on either side of static only where
    ``library.zone_damping`` is, the square of the deflection only where ``library.deflection_squared``
    is), then the input features offered
    (``library.input_features``), once each."""
    out: list[tuple[str, float | None]] = []
    shapes = shapes or {}
    for f in FEATURES:
        if f in LAW_SHAPE_FEATURES:
            continue   # a friction law's shape, fitted once a friction is stable (learned_candidate)
        if f in POSITION_DAMPING and not bool(cfg["library.position_damping"]):
            continue
        if f == EVEN_SPRING and not bool(cfg["library.deflection_squared"]):
            continue
        if f == ZONE_DAMPING and not bool(cfg["library.zone_damping"]):
            continue
        shape = shape_of(f, cfg)
        if shape in shapes:
            out.append((f, float(shapes[shape])))
        elif f in _SHAPE_VALUES:
            out += [(f, float(v)) for v in cfg[_SHAPE_VALUES[f]]]
        else:
            out.append((f, None))
    for f in cfg["library.input_features"]:
        if f not in INPUT_FEATURES:
            raise ValueError(f"force_shape.yaml: library.input_features: unknown input feature {f!r}; known: "
                             f"{', '.join(INPUT_FEATURES)}")
        out.append((f, None))
    return out


@dataclass
class Design:
    """The regression problem: whitened, band-passed rows (three channels per sample, every drive),
    the columns' meaning and each row's drive."""

    X: np.ndarray
    y: np.ndarray
    groups: np.ndarray
    columns: list[Column]


def without_inputs(design: Design) -> Design:
    """``design`` without its input features' columns: the regression of the states alone."""
    keep = [j for j, c in enumerate(design.columns) if c.feature not in INPUT_FEATURES]
    return Design(design.X[:, keep], design.y, design.groups, [design.columns[j] for j in keep])


def columns_of(entries: list[tuple[str, float | None]]) -> list[Column]:
    return [Column(f, a, s) for f, s in entries for a in AXLES]


@dataclass
class Selection:
    """The stable dependences: per (feature, axle) its selection frequency (per :func:`group_key`: a
    rotation harmonic's sine and cosine count together), chosen shape value, fitted coefficient [N] and
    share of the fitted force's variance; ``order`` strongest first."""

    frequency: dict[tuple[str, str], float]
    stable: list[Column]
    coef: np.ndarray
    share: np.ndarray
    resamples: int
    #: per (law family, axle) (:func:`law_key`) the fraction of the resamples that can test it selecting any member
    law_frequency: dict[tuple[str, str], float] = field(default_factory=dict)
    #: the stable dependences that stand for a stable law family no single member of which is stable
    by_law: tuple[tuple[str, str], ...] = ()

    @property
    def dependences(self) -> list[str]:
        """Feature names, strongest first, each once (interface.md ``unlisted_force.dependences``)."""
        seen: list[str] = []
        for k in np.argsort(-self.share):
            if self.stable[k].feature not in seen:
                seen.append(self.stable[k].feature)
        return seen

    @property
    def axles(self) -> list[str]:
        return sorted({c.axle for c in self.stable}, key=AXLES.index)

    @property
    def leading(self) -> str | None:
        """The strongest stable dependence, a rotation harmonic's sine and cosine counted together (the
        feature of the pair with the larger share); None when nothing is stable."""
        if not self.stable:
            return None
        total: dict[str, float] = {}
        for c, q in zip(self.stable, self.share):
            total[group_of(c.feature)] = total.get(group_of(c.feature), 0.0) + float(q)
        lead = max(total, key=lambda g: total[g])
        return next(f for f in self.dependences if group_of(f) == lead)

    @property
    def input_led(self) -> bool:
        """Whether the strongest stable dependence (:attr:`leading`) is an input feature (the road under the
        wheel, the wheel's rotation): the missing force follows an input the recording lacks, not a state."""
        return self.leading in INPUT_FEATURES

    @property
    def input_kind(self) -> str | None:
        """What the leading input feature follows (``road``, ``wheel_rotation``), None when not input-led."""
        lead = self.leading
        return INPUT_KIND[lead] if lead in INPUT_FEATURES else None

    def physics(self) -> "Selection":
        """The selection without its input features (what a learned term may stand for), shares renormalised."""
        keep = [k for k, c in enumerate(self.stable) if c.feature not in INPUT_FEATURES]
        share = self.share[keep]
        stable = [self.stable[k] for k in keep]
        return Selection(self.frequency, stable, self.coef[keep], share / max(float(share.sum()), 1e-300),
                         self.resamples, self.law_frequency, _kept(self.by_law, stable))

    def listed_rivals(self) -> list[str]:
        """The listed TERMs that stand for every stable dependence (empty when one has none)."""
        rivals = [LISTED_FOR.get(c.feature) for c in self.stable]
        return [] if any(r is None for r in rivals) else sorted(set(r for r in rivals if r))

    def description(self, coef: np.ndarray | None = None, shapes: dict | None = None,
                    reach: Reach | None = None) -> str:
        """One sentence in words, strongest dependence first, each with its axles, sense (from ``coef``,
        the fitted coefficients in :attr:`stable` order, when given; else the regression's) and share; a
        knee or free play at its fitted value in ``shapes`` (``{"knee_velocity": m/s, "free_play": m}``)
        when given, else at the value the regression selected; a damper force's rebound ratio and a friction's
        fitted law (levels sliding and at rest, creep, presliding travel) when ``shapes`` has them. ``reach``
        (:func:`drives_reach`): a force met beyond a gap says how deep beyond it the drives reach
        (:func:`_reach_words`), a zone damping with one end beyond the drives' reach on each of its axles is
        worded as the stop the drives saw (:data:`ZONE_ONE_END`)."""
        coef = self.coef if coef is None else np.asarray(coef, float)
        shapes = shapes or {}
        parts = []
        worded: set[str] = set()
        for feature in self.dependences:
            ks = [k for k in np.argsort(-self.share) if self.stable[k].feature == feature]
            c = self.stable[ks[0]]
            shape = _gap_name(feature, shapes)
            value = float(shapes[shape]) if shape in shapes else c.shape or 0.0
            rebound = float(shapes.get(REBOUND_GAP, value)) if feature == ZONE_DAMPING else value
            w = WORDS[feature].format(knee=value, gap_mm=1e3 * value, rgap_mm=1e3 * rebound, tau=value)
            if feature in GAP_SIDES and reach is not None:
                w = _reach_words(w, feature, value, rebound, [reach.of(feature, self.stable[k].axle) for k in ks])
            if feature in DAMPER_OIL and REBOUND_RATIO in shapes:
                w += f", in rebound {float(shapes[REBOUND_RATIO]):.1f}x what it gives in compression"
            more, less = SENSE[feature]
            senses = [more if _sense(self.stable[k], coef[k], value, shapes) > 0 else less for k in ks]
            where = ", ".join(f"{self.stable[k].axle} {s} {100 * self.share[k]:.0f} %" for k, s in zip(ks, senses))
            if feature in SMOOTH_LAW_SPRINGS:   # the part once per axle, with the strongest spring there
                axles_here = {self.stable[k].axle for k in ks} - worded
                w += _progressive_words(self, shapes, axles_here)
                worded |= axles_here
            parts.append(f"{w} ({where})")
        law = _friction_law_words(self, shapes)
        if law:
            parts.append(law)
        axles = self.axles
        return f"A force the model lacks: {'; '.join(parts)}; " \
               f"{f'{axles[0]} axle only' if len(axles) == 1 else 'both axles'}."


@dataclass(frozen=True)
class Reach:
    """How deep the drives reach, per axle ``(bump, rebound)`` [m, both >= 0]: the deepest deflections from static
    of the model as run, either corner of the axle, in every drive (``every``) and in the drives whose damper at
    that corner holds oil (``with_oil``: a force of the damper's oil acts in no other)."""

    every: dict[str, tuple[float, float]]
    with_oil: dict[str, tuple[float, float]]

    def of(self, feature: str, axle: str) -> tuple[float, float]:
        """The reach that tells what ``feature`` does on ``axle``: with oil for a damping, else every drive's."""
        return (self.with_oil if feature in DAMPINGS else self.every)[axle]


def _reach_words(words: str, feature: str, gap: float, rebound_gap: float, reach: list[tuple[float, float]]) -> str:
    """The ``words`` of a force met beyond a gap (``gap`` of bump, ``rebound_gap`` of rebound [m]) with how deep
    beyond it the drives reach (``reach``: per axle it acts on, :meth:`Reach.of`): the range the fitted force is
    seen over, and beyond it an extrapolation. A zone with one end beyond the reach on every one of its axles is the
    stop the drives saw (:data:`ZONE_ONE_END`: its other side is zero in every drive, so nothing in them tells a
    zone from a stop)."""
    bump, rebound = max(b for b, _ in reach), max(r for _, r in reach)
    oil = " with oil in the damper" if feature in DAMPINGS else ""
    if feature == ZONE_DAMPING:
        gaps, deepest = {"bump": gap, "rebound": rebound_gap}, {"bump": bump, "rebound": rebound}
        for near, far in (("bump", "rebound"), ("rebound", "bump")):
            if gaps[far] > deepest[far] and gaps[near] < deepest[near]:
                return ZONE_ONE_END.format(near=near, far=far, near_mm=1e3 * gaps[near], far_mm=1e3 * gaps[far],
                                           reach_mm=1e3 * deepest[far], stage=STOP_STAGE[near])
        return (f"{words}, seen in these drives to {1e3 * bump:.0f} mm of bump and {1e3 * rebound:.0f} mm of "
                f"rebound{oil}")
    depth = bump if GAP_SIDES[feature] == "bump" else rebound
    if gap >= depth:
        return (f"{words}, beyond the deepest {GAP_SIDES[feature]} these drives reach{oil} ({1e3 * depth:.1f} mm): "
                f"met in none of them")
    return f"{words}, seen in these drives to {1e3 * depth:.0f} mm of {GAP_SIDES[feature]}{oil}"


def drives_reach(f, fit) -> Reach:
    """How deep the drives of the fitted finder ``f`` reach with the model of ``fit`` (a
    :class:`~.fit.FitResult`): its simulated deflections from static (:class:`Reach`). How far the drives tell
    what a force met beyond a gap does."""
    names = [f"DEFL_{w}" for w in CORNER_NAMES]
    ev = f.evaluator_
    oil = ev.rows(fit.structure, fit.x)[:, P_INDEX["OIL"]:P_INDEX["OIL"] + len(CORNER_NAMES)]
    deep = {k: np.zeros((2, len(CORNER_NAMES))) for k in ("every", "with_oil")}   # (bump, rebound) per corner
    for r in range(len(f.cases_)):
        d = ev.simulate_outputs(fit.structure, fit.x, r, names)
        here = np.vstack([d.max(axis=0), -d.min(axis=0)])
        deep["every"] = np.maximum(deep["every"], here)
        deep["with_oil"] = np.where(oil[r] > 0.0, np.maximum(deep["with_oil"], here), deep["with_oil"])
    return Reach(**{k: {a: (float(v[0, list(ij)].max()), float(v[1, list(ij)].max())) for a, ij in AXLE_CORNERS.items()}
                    for k, v in deep.items()})


def _friction_law_words(sel: Selection, values: dict) -> str:
    """Words on a learned friction's fitted law (:func:`friction_law`; ``values`` the fitted coefficients
    and shapes by name): per axle with a plain level its sliding level and its level at rest (the sliding
    level plus the weakening) with the Stribeck velocity, the creep's force at its creep velocity, and the
    presliding travel; none when the law is not fitted. The numbers say whether the contact sticks (a level
    at rest at or above the sliding one) or creeps (a level at rest near none, the force built by the creep)."""
    if not any(c.feature in FRICTION_LIKE for c in sel.stable):
        return ""

    def num(name: str) -> float | None:
        v = values.get(name)
        return float(v) if isinstance(v, (int, float)) else None

    out = []
    levels = []
    rising = []   # per axle with a plain level: its level at rest below the sliding one
    for a in AXLES:
        level, weak = num(Column("sign_velocity", a).coefficient), num(Column(WEAKENING, a).coefficient)
        if level is not None and weak is not None:
            levels.append(f"{a} {_newtons(level)} sliding and {_newtons(level + weak)} at rest")
            rising.append(weak < 0.0)
    vs = num(STRIBECK_VELOCITY)
    if levels:
        out.append(", ".join(levels) + (f" (Stribeck velocity {1e3 * vs:.1f} mm/s)" if vs is not None else ""))
    creep = [(a, num(Column(CREEP, a).coefficient)) for a in AXLES]
    vc = num(CREEP_VELOCITY)
    if vc is not None and any(c is not None for _, c in creep):
        at = ", ".join(f"{a} {_newtons(c)}" for a, c in creep if c is not None)
        out.append(f"creeping (viscous) below {1e3 * vc:.1f} mm/s ({at} at it)")
    xp = num(PRESLIDING)
    if xp is not None:
        out.append(f"presliding travel {1e6 * xp:.0f} um")
    if rising and all(rising) and vs is not None:
        # a level that builds with the sliding velocity is a velocity-saturating force, which a damping valve
        # that blows off or a bleed gives alike (Dixon, The Shock Absorber Handbook, 2007, ch. 5): say so
        out.append(f"its level at rest below the sliding one, so the force grows with the sliding velocity over "
                   f"about {1e3 * vs:.0f} mm/s as a damping that saturates there does (a valve's blow-off); a "
                   f"damper rig at 1-50 mm/s tells them apart (a friction holds at each reversal, a damping "
                   f"starts from none)")
    return f"the friction's law as fitted: {', '.join(out)}" if out else ""


def _newtons(v: float) -> str:
    """A force [N] to the newton, a value that rounds to none without a sign ("0 N", never "-0 N")."""
    return f"{round(v):d} N"


def _gap_name(feature: str, values: dict) -> str | None:
    """The learned term's shape parameter ``feature`` is met beyond or shaped by (:data:`_SHAPE_OF`): for a feature met
    in rebound the rebound gap where ``values`` (by name) hold one apart, else its own shape."""
    return REBOUND_GAP if feature in REBOUND_GAPPED and REBOUND_GAP in values else _SHAPE_OF.get(feature)


def _words_depth(gap: float) -> float:
    """The depth beyond a contact's ``gap`` [m] at :data:`WORDS_DEFLECTION_M` from static, over d_ref (0 within it)."""
    return max(WORDS_DEFLECTION_M - gap, 0.0) / float(shape_defaults()["deflection_ref"])


def _sense(c: Column, coef: float, gap: float, values: dict) -> float:
    """The sign the words give the dependence ``c`` of fitted coefficient ``coef``: the coefficient's, or for a
    contact with its square fitted (:data:`CONTACT_SQUARE`, in ``values`` by name) its whole force
    :data:`WORDS_DEFLECTION_M` beyond static in its sense, beyond its ``gap`` (a corner fitted slightly negative under
    a square that carries the contact is a stiffer contact, not a softer one)."""
    square = values.get(Column(CONTACT_SQUARES[c.feature], c.axle).coefficient) if c.feature in CONTACT_SQUARES \
        else None
    if not isinstance(square, (int, float)) or square == 0.0:
        return float(coef)
    depth = _words_depth(gap)
    return float(coef) * depth + float(square) * depth * depth


def _progressive_words(sel: Selection, values: dict, axles: set[str]) -> str:
    """Words on a spring law's fitted progressive part on ``axles`` (:func:`spring_law`; ``values`` the
    fitted coefficients by name, each its force at the learned term's deflection_ref): its force at
    :data:`WORDS_DEFLECTION_M` of bump; none when not fitted."""
    cube = (WORDS_DEFLECTION_M / float(shape_defaults()["deflection_ref"])) ** 3
    out = []
    for c in (c for c in spring_law(sel) if c.axle in axles):
        v = values.get(c.coefficient)
        if isinstance(v, (int, float)) and v != 0.0:
            out.append(f"{c.axle} {'+' if v > 0 else '-'}{abs(float(v)) * cube:.0f} N at "
                       f"{1e3 * WORDS_DEFLECTION_M:.0f} mm")
    words = f", with a smooth progressive part (the cube of the deflection: {', '.join(out)})" if out else ""
    out = []
    for c in (c for c in spring_law(sel, CONTACT_SQUARE) if c.axle in axles):
        v = values.get(c.coefficient)
        if isinstance(v, (int, float)) and v != 0.0:
            bump = c.feature == CONTACT_SQUARES["bump_contact"]
            gap = float(values.get(_gap_name("bump_contact" if bump else "rebound_contact", values) or "", 0.0))
            at = abs(float(v)) * _words_depth(gap) ** 2
            out.append(f"{c.axle} {'+' if v > 0 else '-'}{at:.0f} N at {1e3 * WORDS_DEFLECTION_M:.0f} mm of "
                       f"{'bump' if bump else 'rebound'}")
    if out:
        words += f", progressive in the depth of its contact (its square: {', '.join(out)})"
    return words


@dataclass(frozen=True)
class _DriveStats:
    """One drive's sufficient statistics of the least-squares problem: ``X'X``, ``X'y``, ``y'y``, rows."""

    G: np.ndarray
    b: np.ndarray
    c: float
    n: int

    @classmethod
    def of(cls, X: np.ndarray, y: np.ndarray) -> "_DriveStats":
        return cls(X.T @ X, X.T @ y, float(y @ y), len(y))


def _forward_cv(stats: dict[int, _DriveStats], pick: np.ndarray, max_features: int) -> np.ndarray:
    """Columns selected by forward stepwise selection on the drives ``pick`` (a drive drawn twice counts
    twice), each step adding the column whose least-squares fit together with those chosen before predicts
    the left-out drives best (leave one drive, all its copies, out; mean over the drives of the per-sample
    squared error), up to ``max_features``; the count, none included, then chosen on the same left-out
    errors by the one-standard-error rule (Hastie, Tibshirani and Friedman, The Elements of Statistical
    Learning, 2009, 3.3.2 and 7.10). "None" is a count: a target the features do not predict on other drives
    selects nothing.

    Why each column is chosen on left-out drives, not by its correlation with the target on all of them (a
    matching pursuit's greedy step): two dependences whose effects correlate over the drives (a plain
    friction level and one that grows with the amplitude, r 0.85 on a bump crossing and a sine steer) are
    told apart by which of them holds across drives, while the in-sample correlation favours the one that
    also follows what the model's structure misses on the drives at hand, so the resamples split their
    votes between the two and neither is stable. Everything from the drives' sufficient statistics, so a
    resample costs no pass over the samples (scikit-learn's ``SequentialFeatureSelector`` would refit on the
    rows for every column, fold and step)."""
    uniq, copies = np.unique(pick, return_counts=True)
    G = sum(m * stats[g].G for g, m in zip(uniq, copies))
    b = sum(m * stats[g].b for g, m in zip(uniq, copies))
    keep = np.flatnonzero(np.diag(G) > 0)
    sel = np.zeros(len(b), bool)
    if not len(keep):
        return sel
    ridge = 1e-9 * float(np.mean(np.diag(G)[keep]))   # a column absent from a fold's training drives: coefficient 0
    train = [(stats[g], G - m * stats[g].G, b - m * stats[g].b) for g, m in zip(uniq, copies)]
    chosen: list[int] = []
    err = [[t.c / t.n for t, _, _ in train]]
    for _ in range(min(max_features, len(keep))):
        cand = np.array([j for j in keep if j not in chosen], np.int64)
        if not len(cand):
            break
        idx = np.column_stack([np.tile(chosen, (len(cand), 1)).astype(np.int64), cand])
        eye = ridge * np.eye(idx.shape[1])
        e = np.empty((len(train), len(cand)))
        for f, (t, Gt, bt) in enumerate(train):
            w = np.linalg.solve(Gt[idx[:, :, None], idx[:, None, :]] + eye, bt[idx][..., None])[..., 0]
            e[f] = (t.c - 2.0 * np.sum(w * t.b[idx], axis=1)
                    + np.einsum("ci,cij,cj->c", w, t.G[idx[:, :, None], idx[:, None, :]], w)) / t.n
        step = int(np.argmin(e.mean(axis=0)))
        chosen.append(int(cand[step]))
        err.append(list(e[:, step]))
    errs = np.array(err).T                    # fold x count
    mean, se = errs.mean(axis=0), errs.std(axis=0, ddof=1) / math.sqrt(len(errs))
    best = int(np.argmin(mean))
    k = int(np.flatnonzero(mean <= mean[best] + se[best])[0])
    sel[chosen[:k]] = True
    return sel


def _testable(acts: dict[int, set], pick: np.ndarray) -> set:
    """The dependences a resample ``pick`` can test: those that act (a column not identically zero) on at
    least two of its distinct drives, one to fit and one left out (``acts``: per drive, the dependences
    acting on it)."""
    seen: Counter = Counter()
    for g in np.unique(pick):
        seen.update(acts[int(g)])
    return {k for k, n in seen.items() if n >= 2}


def drive_resamples(drives: np.ndarray, cfg: dict) -> list[tuple[np.ndarray, float]]:
    """The drive-bootstrap resamples of the stability selection, each with its weight: ``selection.resamples``
    drawn at random (weight 1 each, seeded by ``selection.seed``); or, with ``selection.exact_bootstrap`` and at
    most ``selection.exact_bootstrap_max`` of them, every multiset of ``len(drives)`` draws from ``drives`` with
    its multinomial probability ``n! / (prod m_i! n^n)``: the frequencies the random draws estimate, without their
    Monte Carlo spread (about 0.10 at 24 draws; 462 multisets of six drives). A resample of one distinct drive
    is kept here and skipped by :func:`select` (it can test nothing)."""
    n = len(drives)
    if bool(cfg["selection.exact_bootstrap"]) and math.comb(2 * n - 1, n) <= int(cfg["selection.exact_bootstrap_max"]):
        out = []
        for pick in combinations_with_replacement(drives, n):
            _, m = np.unique(pick, return_counts=True)
            w = math.factorial(n) / math.prod(math.factorial(int(k)) for k in m) / n ** n
            out.append((np.array(pick), w))
        return out
    rng = np.random.default_rng(int(cfg["selection.seed"]))
    return [(rng.choice(drives, size=n, replace=True), 1.0) for _ in range(int(cfg["selection.resamples"]))]


def select(design: Design, cfg: dict | None = None) -> Selection | None:
    """Stability selection over drive-bootstrap resamples (module docstring); None when fewer than two
    drives have rows or nothing is stable. A dependence is counted per :func:`group_key` (a rotation
    harmonic's sine and cosine once, as one), and a stable pair keeps both columns.

    A dependence's selection frequency counts the resamples that can test it: those with at least two
    distinct drives on which it acts (:func:`_testable`). A force that acts only on some drives (a valve of
    the rear dampers, zero where they are oil-empty; a knee the sine steers' deflection velocities never
    reach) can be selected from, and its prediction checked on, those drives only; a resample without two
    of them says nothing about it: it is counted neither as a vote against it nor, when the count chosen for
    the other dependences takes it in, for it."""
    cfg = settings() if cfg is None else cfg
    drives = np.unique(design.groups)
    if len(drives) < 2:
        return None
    stats = {int(g): _DriveStats.of(design.X[design.groups == g], design.y[design.groups == g]) for g in drives}
    max_f = int(cfg["selection.max_features"])
    keys = [group_key(c.key) for c in design.columns]
    laws = [law_key(k) for k in keys]
    acting = {g: np.flatnonzero(np.diag(t.G) > 0.0) for g, t in stats.items()}
    acts = {g: {keys[j] for j in js} for g, js in acting.items()}
    law_acts = {g: {laws[j] for j in js} for g, js in acting.items()}
    # weighted counts (a resample's weight, :func:`drive_resamples`)
    counts: defaultdict = defaultdict(float)
    testable: defaultdict = defaultdict(float)
    law_counts: defaultdict = defaultdict(float)
    law_testable: defaultdict = defaultdict(float)
    shapes: dict[tuple[str, str], defaultdict] = {}
    done = 0
    for pick, w in drive_resamples(drives, cfg):
        if len(np.unique(pick)) < 2:
            continue
        sel = _forward_cv(stats, pick, max_f)
        done += 1
        can, law_can = _testable(acts, pick), _testable(law_acts, pick)
        chosen = np.flatnonzero(sel)
        for acc, ks in ((testable, can), (law_testable, law_can), (counts, {keys[j] for j in chosen} & can),
                        (law_counts, {laws[j] for j in chosen} & law_can)):
            for k in ks:
                acc[k] += w
        for j in chosen:
            if keys[j] in can:
                shapes.setdefault(design.columns[j].key, defaultdict(float))[design.columns[j].shape] += w
    if done == 0:
        return None
    # in the design's column order, not the counters' (filled from sets, whose order follows the interpreter's
    # string hashing): the stable set's order, and so the learned term's parameters, the same in every process
    freq = {k: counts[k] / testable[k] for k in dict.fromkeys(keys) if counts[k]}   # never 0 / 0: testable
    law_freq = {k: law_counts[k] / law_testable[k] for k in dict.fromkeys(laws) if law_counts[k]}
    min_frequency = float(cfg["selection.min_frequency"])
    stable_keys = [k for k, q in freq.items() if q >= min_frequency]
    by_law = _law_representatives(freq, law_freq, stable_keys, min_frequency)
    stable_keys += by_law
    if not stable_keys:
        return Selection(freq, [], np.zeros(0), np.zeros(0), done, law_freq)
    members = [(f, a) for g, a in stable_keys for f in dict.fromkeys(c.feature for c in design.columns)
               if group_key((f, a)) == (g, a)]
    # the shape most resamples chose (the first of equals, as Counter.most_common)
    cols = [Column(f, a, max(shapes[(f, a)].items(), key=lambda kv: kv[1])[0] if (f, a) in shapes else None)
            for f, a in members]
    idx = [design.columns.index(c) for c in cols]
    A = design.X[:, idx]
    coef, *_ = np.linalg.lstsq(A, design.y, rcond=None)
    share = _shares(A, coef)
    keep = share >= float(cfg["selection.min_share"])
    cols = [c for c, k in zip(cols, keep) if k]
    coef, share = coef[keep], share[keep]
    return Selection(freq, cols, coef, share, done, law_freq, _kept(by_law, cols))


def _shares(A: np.ndarray, coef: np.ndarray) -> np.ndarray:
    """Each column's share of the variance of the fitted force ``A @ coef`` (its own contribution's variance
    over the sum's, normalised to 1 over the columns); a single column carries all of it."""
    if A.shape[1] == 1:
        return np.ones(1)
    contrib = A * coef
    share = np.var(contrib, axis=0) / max(float(np.var(contrib.sum(axis=1))), 1e-300)
    return share / max(float(share.sum()), 1e-300)


def extended(old: Selection, fitted: np.ndarray, new: Selection, design: Design,
             cfg: dict | None = None) -> Selection | None:
    """The learned term's selection ``old`` (its coefficients as fitted: ``fitted``, in ``old.stable`` order)
    extended by the stable dependences of ``new`` it lacks, read off the residual the learned term leaves
    (``design``, :func:`design_for` with the term in the structure and its shapes held): a force of two or
    more dependences of which one regression found the strongest (a position-sensitive damper's damping beyond
    a gap in bump at the front, then in rebound and at the rear). None when ``new`` adds no (feature, axle).

    The coefficients: the old ones as fitted plus, with the added ones, the least-squares fit of all their
    columns to the residual (the old ones' columns are increments on the fitted term); shares from that sum.
    An added dependence that carries less than ``selection.min_share`` of the force is left out, as in
    :func:`select`; the old ones stay."""
    cfg = settings() if cfg is None else cfg
    have = {c.key for c in old.stable}
    added = [c for c in new.stable if c.key not in have]
    if not added:
        return None
    by_key = {c.key: j for j, c in enumerate(design.columns)}   # one column per key: the shapes are held
    cols = list(old.stable) + added
    A = design.X[:, [by_key[c.key] for c in cols]]
    step, *_ = np.linalg.lstsq(A, design.y, rcond=None)
    coef = step + np.concatenate([np.asarray(fitted, float), np.zeros(len(added))])
    share = _shares(A, coef)
    keep = np.arange(len(cols)) < len(old.stable)
    keep |= share >= float(cfg["selection.min_share"])
    if not keep[len(old.stable):].any():
        return None
    cols = [c for c, k in zip(cols, keep) if k]
    coef, share = coef[keep], share[keep] / max(float(share[keep].sum()), 1e-300)
    frequency = {**new.frequency, **old.frequency}
    law_frequency = {**new.law_frequency, **old.law_frequency}
    return Selection(frequency, cols, coef, share, old.resamples, law_frequency, _kept(old.by_law + new.by_law, cols))


def _mirrored(sel: Selection) -> list[tuple[Column, tuple[str, str]]]:
    """Each stable dependence of ``sel`` of a law family (:data:`LAW_OF`) on one axle, with its (feature, other
    axle) key, where ``sel`` does not hold that key already: what :func:`other_axle` and
    :func:`other_axle_extended` offer."""
    have = {c.key for c in sel.stable}
    out = []
    for c in sel.stable:
        if law_key(c.key)[0] not in LAW_FAMILIES or c.axle not in AXLES:
            continue
        key = (c.feature, next(a for a in AXLES if a != c.axle))
        if key not in have:
            out.append((c, key))
    return out


def other_axle_extended(old: Selection, fitted: np.ndarray, design: Design) -> Selection | None:
    """The learned term's selection ``old`` (its coefficients as fitted: ``fitted``) with each of its
    law-family dependences (:data:`LAW_OF`) also on the other axle, at the shape the term holds (``design``, the
    regression against the residual the term leaves with its shapes held, has one column per key), the added
    coefficients starting at 0, for the fit to size (``fit.other_axle_extends``; :func:`fitted_shares` then
    applies ``fit.other_axle_min_share`` to the fitted force). Not the regression's share at the offer: the residual
    it reads is the one the calibration left with the other axle's force absent, and a calibration value of
    that axle (its wheel rate, its oil-empty damper) has taken up what it could of that force, which only a fit
    that frees both can give back. Why, in physical terms: the two axles' dampers, springs and stops are most
    often of one design (:func:`other_axle`), and a force that is smaller on one axle (a twin-tube's low gas
    charge beside a monotube's) stays below the stability selection's reach there. None when nothing is added,
    or when listed terms would stand for every dependence of the result."""
    by_key = {c.key: c for c in design.columns}
    added = [by_key[key] for _, key in _mirrored(old) if key in by_key]
    if not added:
        return None
    cols = list(old.stable) + added
    coef = np.concatenate([np.asarray(fitted, float), np.zeros(len(added))])
    alt = Selection(old.frequency, cols, coef, np.concatenate([old.share, np.zeros(len(added))]), old.resamples,
                    old.law_frequency, old.by_law)
    return None if alt.listed_rivals() else alt


def fitted_shares(sel: Selection, fitted: np.ndarray, design: Design, n_old: int,
                  cfg: dict | None = None) -> Selection | None:
    """``sel`` with its coefficients as fitted (``fitted``, in ``sel.stable`` order) and each column's share of
    the fitted force's variance over ``design``'s rows (:func:`_shares`); None when a column after the first
    ``n_old`` (those an extension added) carries less than ``fit.other_axle_min_share`` of it (``cfg``, default
    ``config/force_shape.yaml``; 0 as shipped: the trial's tests judge the added axle, its share is only said)."""
    cfg = settings() if cfg is None else cfg
    by_key = {c.key: j for j, c in enumerate(design.columns)}
    coef = np.asarray(fitted, float)
    share = _shares(design.X[:, [by_key[c.key] for c in sel.stable]], coef)
    if (share[n_old:] < float(cfg["fit.other_axle_min_share"])).any():
        return None
    return Selection(sel.frequency, list(sel.stable), coef, share, sel.resamples, sel.law_frequency, sel.by_law)


def law_keys(sel: Selection) -> list[tuple[str, str]]:
    """The stable dependences of ``sel`` whose feature belongs to a law family (:data:`LAW_OF`: a spring,
    damping, friction or roll form of one axle), in the selection's order: those whose form the fit may
    decide (:func:`law_members`)."""
    return [c.key for c in sel.stable if law_key(c.key)[0] in LAW_FAMILIES]


def law_members(sel: Selection, key: tuple[str, str], design: Design, cfg: dict | None = None) -> list[Selection]:
    """The other forms the stable dependence ``key`` of ``sel`` may take, for the fit to decide between:
    ``sel`` with it replaced by each other member of its law family (:data:`LAW_OF`) on its axle that some
    resample selected (:attr:`Selection.frequency`; a family offered as a whole lists every member, at 0:
    :func:`spring_on_axle`), or every member of the family on the axle with ``fit.law_members_whole_family``
    (``cfg``, default ``config/force_shape.yaml``: a form no resample chose may still be the one, as the front
    valve of the blind ``unlisted/damper_blow_off`` #3, read as an orifice), and that ``sel`` does not hold
    already, in the order of the vocabulary. The regression reads a form off columns at a few offered shape
    values, linearised at the model as fitted, and the members' columns correlate over a bump crossing and a
    sine steer: it may be sure of the kind and wrong in the form (a hydraulic rebound stop read as a valve
    opening above a knee, selected in every resample; a position-sensitive damper read as a plain viscous
    damping at the rear, where the votes split).

    A member with a shape (a knee, a contact gap) takes the value another stable column of the selection
    holds for it (one value per shape serves the term: :func:`learned_candidate`), else the offered value
    that fits best together with the other columns; the coefficients are the least-squares fit of all the
    columns to ``design``'s target, the shares from it (a member carrying less than ``selection.min_share``
    is still offered: the fit decides). ``key`` standing for its family (:attr:`Selection.by_law`), the member
    does. A member with which listed terms stand for every dependence (:meth:`Selection.listed_rivals`) is
    not offered, as the learned term is not in that case: those listed terms are in the competition already
    (a learned friction at the rear read as growing with the peak deflection alone is the listed amplitude
    friction's business)."""
    cfg = settings() if cfg is None else cfg
    whole = bool(cfg["fit.law_members_whole_family"])
    k = next(j for j, c in enumerate(sel.stable) if c.key == key)
    others = [c for j, c in enumerate(sel.stable) if j != k]
    held = {shape_of(c.feature, cfg): c.shape for c in others if c.shape is not None}
    have = {c.key for c in sel.stable}
    out: list[Selection] = []
    for f in FEATURES:
        member = (f, key[1])
        if member in have or (member not in sel.frequency and not whole) or law_key(member) != law_key(key):
            continue
        shape = shape_of(f, cfg)
        offered = [c for c in design.columns if c.key == member
                   and (c.shape is None or shape not in held or c.shape == held[shape])]
        best = None
        for c in offered:
            cols = sel.stable[:k] + [c] + sel.stable[k + 1:]
            A, coef, rss = _fit_columns(design, cols)
            if best is None or rss < best[0]:
                best = (rss, cols, A, coef)
        if best is None:
            continue   # offered at no shape value the term holds
        _, cols, A, coef = best
        by_law = tuple(member if b == key else b for b in sel.by_law)
        alt = Selection(sel.frequency, cols, coef, _shares(A, coef), sel.resamples, sel.law_frequency, by_law)
        if not alt.listed_rivals():   # listed terms standing for every dependence compete already
            out.append(alt)
    return out


def _fit_columns(design: Design, cols: list[Column]) -> tuple[np.ndarray, np.ndarray, float]:
    """``cols`` of ``design`` fitted to its target by least squares: their matrix, the coefficients and the
    residual sum of squares."""
    A = design.X[:, [design.columns.index(x) for x in cols]]
    coef, *_ = np.linalg.lstsq(A, design.y, rcond=None)
    return A, coef, float(np.sum((design.y - A @ coef) ** 2))


def other_axle(sel: Selection, design: Design, cfg: dict | None = None) -> Selection | None:
    """``sel`` with each stable dependence of a law family (:data:`LAW_OF`) also on the other axle, at the
    shape it holds (else, of the shapes offered there, the one that fits best together with the other
    columns), for the fit to decide: the two axles' dampers, stops and springs are most often of one design,
    and the resamples may split their votes between axles that both carry a force. The coefficients are
    the least-squares fit of all the columns to ``design``'s target, the shares from it; an added column
    that carries less than ``selection.min_share`` of the force is left out, as in :func:`select` (a
    rear jounce bumper's 2 % at the front is no front bumper). None when nothing is added, or when listed
    terms stand for every dependence of the result (they compete already)."""
    cfg = settings() if cfg is None else cfg
    cols = list(sel.stable)
    for c, key in _mirrored(sel):
        offered = [d for d in design.columns if d.key == key]
        if not offered:
            continue
        same = [d for d in offered if d.shape == c.shape]
        cols.append(same[0] if same else min(offered, key=lambda d: _fit_columns(design, cols + [d])[2]))
    if len(cols) == len(sel.stable):
        return None
    A, coef, _ = _fit_columns(design, cols)
    keep = np.arange(len(cols)) < len(sel.stable)
    keep |= _shares(A, coef) >= float(cfg["selection.min_share"])
    if not keep[len(sel.stable):].any():
        return None
    if not keep.all():
        cols = [c for c, k in zip(cols, keep) if k]
        A, coef, _ = _fit_columns(design, cols)
    alt = Selection(sel.frequency, cols, coef, _shares(A, coef), sel.resamples, sel.law_frequency, sel.by_law)
    return None if alt.listed_rivals() else alt


def spring_on_axle(design: Design, axle: str, resamples: int) -> Selection | None:
    """A spring of ``axle`` for the fit to test where the recorded road leads the missing force on that axle
    only and no reading of the states is stable (``fit.spring_where_road_leads_one_axle``): the spring-family
    column (:data:`LAW_OF`) on the axle, at the offered shape, that alone fits ``design``'s target best by least
    squares, standing for its family (:attr:`Selection.by_law`); every other member of the family on the axle at
    frequency 0 (no resample chose any: the family is offered, not a form), so :func:`law_members` offers each
    to the fit. A spring of a law no feature has (a gas charge's even part) moves with the road over a bump
    better than with any one state feature; the fit and the held-out tests decide whether it stands. None when
    the design has no spring column on the axle. ``resamples``: those of the regression that found nothing
    stable (recorded)."""
    cols = [c for c in design.columns if c.axle == axle and LAW_OF.get(c.feature) == "spring"]
    if not cols:
        return None
    fits = []
    for c in cols:
        A = design.X[:, [design.columns.index(c)]]
        coef, *_ = np.linalg.lstsq(A, design.y, rcond=None)
        fits.append((float(np.sum((design.y - A @ coef) ** 2)), c, coef))
    _, col, coef = min(fits, key=lambda f: f[0])
    return Selection({c.key: 0.0 for c in cols}, [col], coef, np.ones(1), resamples, {law_key(col.key): 0.0},
                     (col.key,))


def _kept(by_law, cols: list[Column]) -> tuple[tuple[str, str], ...]:
    """The keys of ``by_law`` that are still among the columns ``cols``."""
    keys = {c.key for c in cols}
    return tuple(k for k in by_law if k in keys)


def _law_representatives(freq: dict, law_freq: dict, stable_keys: list, min_frequency: float) -> list:
    """Per law family (and axle) selected in at least ``min_frequency`` of the resamples that can test it and
    none of whose members is stable on its own, the member selected most often (cluster stability selection:
    Faletto and Bien 2022, arXiv:2201.00494, whose clusters' votes are pooled the same way; ties: the first
    in the vocabulary's order): the family is a stable dependence, its form the one the resamples preferred."""
    stable_laws = {law_key(k) for k in stable_keys}
    reps = []
    for law, q in sorted(law_freq.items()):
        if law[0] not in LAW_FAMILIES or q < min_frequency or law in stable_laws:
            continue
        members = [k for k in freq if law_key(k) == law]
        reps.append(max(members, key=lambda k: (freq[k], -FEATURES.index(k[0]))))
    return reps


def _fitted_shapes(sel: Selection, cfg: dict) -> dict[str, float]:
    """The shape values a learned term of ``sel`` fits (``{shape: start}``), each from the value the regression
    picked for the first stable dependence that has it; with the gaps held apart a zone's one gap starts both."""
    shapes: dict[str, float] = {}
    for c in sel.stable:
        if c.shape is not None:
            slots = shapes_of(c.feature, cfg)   # its own shape first
            for name in slots if bool(cfg["fit.rebound_gap"]) else slots[:1]:
                shapes.setdefault(name, c.shape)
    return shapes


def learned_candidate(sel: Selection, cfg: dict | None = None, progressive: bool | str = True) -> Candidate:
    """The learned term as a finder candidate: one coefficient [N] per stable (feature, axle), neutral 0,
    and the knee / free play it selected as a free shape value (neutral: the selected value; range: the
    config's, the plausible range of the physics, not a band around the library value the regression picked,
    which held a valve's knee at its edge). A stable
    friction-like dependence brings its law's shape (:func:`friction_law`): the presliding travel and,
    per axle with a plain friction level (``sign_velocity``), a level at rest above the sliding one that
    falls over a Stribeck velocity and the level's growth with the compression (coefficients neutral 0,
    after the stable ones). A stable force of the
    damper's oil (an orifice, a valve) brings its rebound ratio (:func:`damper_law`), a stable contact spring
    its smooth progressive part (:func:`spring_law`, a coefficient neutral 0 after those of the friction law;
    left out with ``progressive`` False: the finder fits the plain contact first; ``progressive`` a form of
    :func:`spring_law`, that form, True its cube)."""
    cfg = settings() if cfg is None else cfg
    bound = float(cfg["fit.coefficient_bound_N"])
    params = []
    axle_of: list[str | None] = []
    for c, v in zip(sel.stable, sel.coef):
        step = max(abs(float(v)) / 5.0, 1.0)
        params.append(CandParam(c.coefficient, "N", 0.0, -bound, bound, step,
                                f"coefficient of {c.feature}, {c.axle} axle"))
        axle_of.append(c.axle)
    law, law_shapes = friction_law(sel, cfg)
    law_shapes.update(damper_law(sel, cfg))
    law_words = {WEAKENING: ("fit.weakening_step_N", "the friction's level at rest above its sliding level"),
                 LEVEL_GROWTH: ("fit.level_growth_step_N", "the friction's level at d_ref of bump over static"),
                 CREEP: ("fit.creep_step_N", "the friction's creep force at the creep velocity")}
    for c in law:
        step_key, words = law_words[c.feature]
        params.append(CandParam(c.coefficient, "N", 0.0, -bound, bound, float(cfg[step_key]),
                                f"coefficient of {c.feature}, {c.axle} axle: {words}"))
        axle_of.append(c.axle)
    bending = spring_law(sel, CUBE if progressive is True else str(progressive)) if progressive else []
    for c in bending:
        what = ("the contact spring's smooth progressive part, its force at d_ref" if c.feature == PROGRESSIVE else
                "the contact's progressive part in the square of its depth, its force at d_ref beyond the gap")
        params.append(CandParam(c.coefficient, "N", 0.0, -bound, bound, float(cfg["fit.progressive_step_N"]),
                                f"coefficient of {c.feature}, {c.axle} axle: {what}"))
        axle_of.append(c.axle)
    law = law + bending
    shapes = _fitted_shapes(sel, cfg)
    for name, value in shapes.items():
        p = LEARNED_FORCE.params[LEARNED_FORCE.param_index(name)]
        lo, hi = (float(v) for v in cfg[_SHAPE_RANGE[name]])
        step = value / 5 if value > 0 else (hi - lo) / 50   # a contact at static (gap 0): a step of its range
        params.append(CandParam(name, p.unit, value, lo, hi, step, p.meaning + " (one value for both axles)",
                                shape=True))
        users = {c.axle for c in sel.stable if c.shape is not None and name in shapes_of(c.feature, cfg)}
        axle_of.append(users.pop() if len(users) == 1 else None)
    for name, (lo, hi, on) in law_shapes.items():
        p = LEARNED_FORCE.params[LEARNED_FORCE.param_index(name)]
        shapes[name] = p.default
        params.append(CandParam(name, p.unit, p.default, lo, hi, p.default / 5,
                                p.meaning + " (one value for both axles)", shape=True))
        axle_of.append(on[0] if len(on) == 1 else None)
    coefs = list(sel.stable) + law
    slots = {name: _slots(name, cfg) for name in shapes}   # a gap to both gaps' parameters unless held apart

    def apply(P, P0, x, model):
        for j, c in enumerate(coefs):
            sl = model.term_param_slice(TERM, f"c_{c.feature}")
            a = sl.start + 2 * AXLES.index(c.axle)
            P[:, a:a + 2] = x[j]
        for j, name in enumerate(shapes, start=len(coefs)):
            for slot in slots[name]:
                P[:, model.term_param_slice(TERM, slot)] = x[j]

    def term_params(x, vp):
        vals: dict[str, dict] = {}
        for j, c in enumerate(coefs):
            e = vals.setdefault(f"c_{c.feature}", {"front": 0.0, "rear": 0.0})
            e[c.axle] += float(x[j])
        out = {k: axle_map(v["front"], v["rear"]) for k, v in vals.items()}
        for j, name in enumerate(shapes, start=len(coefs)):
            for slot in slots[name]:
                out[slot] = axle_map(x[j], x[j])
        return out

    return Candidate(TERM, PHYSICS, sel.description(), tuple(params), apply, tuple(axle_of),
                     "drives that excite the dependences it names: " + ", ".join(sel.dependences), "any",
                     "susp_sim_ros.model.learned_force", term_params=term_params)


def friction_law(sel: Selection, cfg: dict) -> tuple[list[Column], dict[str, tuple[float, float, list[str]]]]:
    """The shape of a learned friction's law, fitted beside its levels: no friction-like dependence stable,
    none. Else the presliding travel of the unit Dahl element (how far a contact deflects before it
    slides is the contact's own: micrometres in a metal joint, up to a millimetre in an elastomer seal lip),
    and on each axle with a plain friction level (``sign_velocity``) how that level varies: a
    ``velocity_weakening`` coefficient and the Stribeck velocity (a lubricated contact's friction falls from
    its level at rest to its sliding level, the Stribeck effect: which it does, and how fast, the drives
    decide; the bump and the sine steer slide at different deflection velocities), and a ``compression``
    coefficient unless that is stable there itself (a Coulomb friction is proportional to its contact's
    normal force, and where the spring's side load or a damper's gas presses a strut's guide or seal that
    force follows the deflection: the level then grows in bump and falls in rebound; a growth the
    resamples' votes split with the plain level, one law family, :data:`LAW_OF`). Where
    ``fit.creep_in_friction_law`` is set, also a creep on every friction axle (``creep_damping``: viscous below
    a creep velocity, one value for both axles; with a weakening that takes the level at rest to none, the law
    of a contact that creeps rather than sticks: its force builds with the sliding velocity). Returns those
    columns (weakening first, creep last) and ``{shape: (lower, upper, axles)}`` (bounds from
    ``config/force_shape.yaml``)."""
    friction = [c for c in sel.stable if c.feature in FRICTION_LIKE]
    if not friction:
        return [], {}
    plain = sorted({c.axle for c in sel.stable if c.feature == "sign_velocity"}, key=AXLES.index)
    axles = sorted({c.axle for c in friction}, key=AXLES.index)
    xp_lo, xp_hi = (float(v) for v in cfg["fit.presliding_range_m"])
    shapes = {PRESLIDING: (xp_lo, xp_hi, axles)}
    if plain:
        vs_lo, vs_hi = (float(v) for v in cfg["fit.stribeck_velocity_range_m_s"])
        shapes[STRIBECK_VELOCITY] = (vs_lo, vs_hi, plain)
    stable = {(c.feature, c.axle) for c in sel.stable}
    growth = [Column(LEVEL_GROWTH, a) for a in plain if (LEVEL_GROWTH, a) not in stable]
    creep: list[Column] = []
    if bool(cfg["fit.creep_in_friction_law"]):
        vc_lo, vc_hi = (float(v) for v in cfg["fit.creep_velocity_range_m_s"])
        shapes[CREEP_VELOCITY] = (vc_lo, vc_hi, axles)
        creep = [Column(CREEP, a) for a in axles]
    return [Column(WEAKENING, a) for a in plain] + growth + creep, shapes


def spring_law(sel: Selection, form: str = CUBE) -> list[Column]:
    """The smooth progressive part of a learned spring law, fitted beside it: on each axle where a spring met
    beyond a gap (:data:`CONTACTS`) or the spring of one sense in bump and rebound (:data:`EVEN_SPRING`) is
    stable and the cube of the deflection is not, a ``deflection_cubed`` coefficient (neutral 0). A contact
    is a spring law to first order: piecewise linear, with one corner at its gap. The elements that make such
    laws stiffen smoothly with travel (an elastomer bumper as it is squeezed, the gas of a damper's charge or
    an air spring compressed, closely wound coils coming to block: Reimpell, Stoll and Betzler, The
    Automotive Chassis, 2nd ed., 2001, ch. 5), and a gas acts on both sides of static, so the corner alone
    reads one side of a law that bends on both. The even spring is a smooth law's first term beyond the
    static rate and the cube its next, with the same sign where the law stiffens in bump (a gas column of
    height h compressed polytropically, exponent n: F0 n (d / h) (1 + (n + 1) / 2 (d / h) + (n + 1) (n + 2) / 6
    (d / h)^2 + ...)), so the square alone reads a law that grows in bump and falls in rebound as one of one
    sense. The resamples split their votes between the members of the spring family (:data:`LAW_OF`) and the
    stable set keeps one member per axle; the fit then decides how much of the cube the drives want, under
    every test of the trial.

    ``form`` :data:`CONTACT_SQUARE`: the progressive part of each stable contact in the square of its depth
    beyond its gap instead (``bump_contact_squared``, ``rebound_contact_squared``: none on an axle with the
    even spring only). The cube bends the law from static on both sides; a contact's own stiffening starts at
    its gap with no jump in rate (an elastomer bumper squeezed, a variable-pitch coil whose rate rises from
    where its first coils close), which the corner and a cube from static read as a jump and a bend."""
    if form == CONTACT_SQUARE:
        return list(dict.fromkeys(Column(CONTACT_SQUARES[c.feature], c.axle) for c in sel.stable
                                  if c.feature in CONTACT_SQUARES))
    if form != CUBE:
        raise ValueError(f"unknown progressive form {form!r}; known: {CUBE}, {CONTACT_SQUARE}")
    stable = {c.key for c in sel.stable}
    axles = sorted({c.axle for c in sel.stable if c.feature in SMOOTH_LAW_SPRINGS},
                   key=AXLES.index)
    return [Column(PROGRESSIVE, a) for a in axles if (PROGRESSIVE, a) not in stable]


def square_from_static(sel: Selection, values: dict[str, float]) -> dict[str, float]:
    """A second start for the fit of ``sel``'s contacts progressive in the square of their depth
    (:data:`CONTACT_SQUARE`), from the plain contacts' fitted ``values`` (by the learned candidate's parameter
    names): each contact's gap at 0 and its corner replaced by the square from static that meets the corner's force
    at twice its gap (c_sq = c d_ref / (4 g), the corner's coefficient c, gap g > 0). A variable-pitch coil's
    k2 max(d, 0)^2 is read by the plain fit as a corner well into the stroke (a spring met beyond 18 mm of bump),
    and freed from there the square stays a bend of that corner: the two are apart in the fit's landscape.
    The values to change, by name; none when every contact is at static already."""
    dref = float(shape_defaults()["deflection_ref"])
    out: dict[str, float] = {}
    for c in sel.stable:
        if c.feature not in CONTACT_SQUARES:
            continue
        gap = _gap_name(c.feature, values) or "contact_gap"
        g = float(values.get(gap, 0.0))
        if g <= 0.0 or c.coefficient not in values:
            continue
        out[Column(CONTACT_SQUARES[c.feature], c.axle).coefficient] = float(values[c.coefficient]) * dref / (4.0 * g)
        out[c.coefficient] = 0.0
        out[gap] = 0.0
    return out


def damper_law(sel: Selection, cfg: dict) -> dict[str, tuple[float, float, list[str]]]:
    """The shape of a learned force of the damper's oil (:data:`DAMPER_OIL`: an orifice, a valve), fitted
    beside its coefficients: none stable, none. Else its rebound ratio, the force in rebound over the force
    at the same speed in compression (neutral 1, a symmetric law): a damper's rebound and compression stages
    are valved apart, so a valve that opens or an orifice changes the two senses by different amounts (the
    regression's features are symmetric, so that they compete with the others on one column each). Returns
    ``{shape: (lower, upper, axles)}`` (bounds from ``config/force_shape.yaml``)."""
    axles = sorted({c.axle for c in sel.stable if c.feature in DAMPER_OIL}, key=AXLES.index)
    if not axles:
        return {}
    lo, hi = (float(v) for v in cfg["fit.rebound_ratio_range"])
    return {REBOUND_RATIO: (lo, hi, axles)}


def _column_candidate(col: Column, step: float, bound: float, cfg: dict) -> Candidate:
    """One library column as a one-parameter candidate (its coefficient [N], in the learned term or, for
    an input feature, in the input term, added to what the structure holds there: a learned term's fitted
    coefficient when the structure has one, else none); the shape value is set only while the coefficient
    acts, so the columns of one feature's knees do not overwrite each other."""
    slots = shapes_of(col.feature, cfg)
    term = INPUT_TERM if col.feature in INPUT_FEATURES else TERM

    def apply(P, P0, x, model):
        if x[0] == 0.0:
            return
        sl = model.term_param_slice(term, f"c_{col.feature}")
        a = sl.start + 2 * AXLES.index(col.axle)
        P[:, a:a + 2] += x[0]   # on top of a learned term's own coefficient where the structure has one
        if col.shape is not None:
            for slot in slots:
                P[:, model.term_param_slice(TERM, slot)] = col.shape

    return Candidate(f"{term}[{col.feature}:{col.axle}:{col.shape}]", PHYSICS, WORDS[col.feature],
                     (CandParam("coef", "N", 0.0, -bound, bound, step),), apply, (col.axle,))


def design_for(f, st0, x0: np.ndarray, idx, cfg: dict | None = None, shapes: dict | None = None) -> Design:
    """The regression problem of the fitted finder ``f`` at the model ``st0`` / ``x0`` over the drives
    ``idx``: the whitened residual (the target is measured - simulated, every compared signal and drive,
    as the finder's criteria see it) against each
    library column's effect on it (the forward-difference Jacobian of the residual in the column's
    coefficient, one batch of simulations). The missing force is thus regressed through the model's own
    dynamics rather than on its smoothed estimate (:mod:`.missing_force`), whose body-mode band and
    uncertainty blur the fast forces of a bump impact (a valve blowing off).

    ``shapes`` (``{shape: value}``, e.g. the contact gap a learned term in ``st0`` holds as fitted): the
    features of those shapes are offered at that value only, since the term has one value of each
    (:func:`extended`)."""
    cfg = settings() if cfg is None else cfg
    entries = library(cfg, shapes)
    cols = columns_of(entries)
    bound = float(cfg["fit.coefficient_bound_N"])
    lib = [_column_candidate(c, float(cfg["library.step_N"]), bound, cfg) for c in cols]
    ev = f.evaluator_
    st = st0.with_(*lib)
    x = st.embed(st0, x0)
    j = np.arange(len(x0), len(x))
    r0, J = fd_jacobian(ev, st, x, idx, cols=j)
    if st0.bias:
        r0, J = debias(ev, r0, idx), debias(ev, J, idx)
    groups = np.concatenate([np.full(ev.n_res[r], r) for r in idx])
    return Design(J, -r0, groups, cols)
