"""Gas spring laws no feature has, end to end on truth the product's model did not make (issues 24 and 26).

The truth is the independent simulator's generator family (``truth_generators/family.py``), seed 1, its six
drives (bump crossings and sine steers, intact / front-empty / rear-empty):

- ``gas/progressive``: the dampers' gas force with a cubic law, 4e6 N/m^3 d^3 per wheel, over a preload. The
  learned force reads a spring met beyond a gap of rebound (the cube about the preload's shifted static is
  stiffer in rebound); beside that contact its smooth progressive part (the cube of the deflection,
  ``force_shape.spring_law``) is fitted in a second stage and kept: without it 2.70x the noise remained
  held out, with it 1.2x (benchmarks/RESULTS.md, 2026-11-30).
- ``gas/polytropic_charge_rear``: the rear dampers' gas charge as a gas law over a preload. Over the bump the
  recorded road height under the rear wheels leads the missing force, on that axle only, and no reading of the
  states is stable: front and rear wheels roll over the same recorded track, so it is no road recorded off and
  no ``unmeasured_input`` is found (before the rule, every seed was; the form was added as a blind test and is
  seen since). A spring of the rear is offered to the fit (``fit.spring_where_road_leads_one_axle``) and named
  as the learned force: it predicts the sine steers, which the road does not reach, held out (before the offer
  nothing was named, 1.79x the noise held out; with it 1.51x, benchmarks/RESULTS.md, 2026-12-01).

Slow: two diagnoses of six drives without the final leave-one-drive-out (one to two minutes each).
"""
from __future__ import annotations

import pytest

from susp_sim_ros.analysis.discrepancy import DiscrepancyFinder, force_shape as fs
from susp_sim_ros.analysis.discrepancy.report import interface_json, verdict
from truth_generators import family

pytestmark = pytest.mark.slow


def _diagnose(form_name: str) -> tuple[DiscrepancyFinder, dict]:
    form = family.FORMS[form_name]
    f = DiscrepancyFinder(variant=form.base, heldout=False).fit([d for _, d in family.make_case(form, 1)])
    return f, {**interface_json(f), "reason": verdict(f)[1]}


def test_a_progressive_gas_spring_is_a_contact_with_its_smooth_progressive_part():
    f, rep = _diagnose("gas/progressive")
    assert rep["verdict"] == "missing_physics"
    learned = [t for t in rep["terms"] if t["name"] == fs.TERM]
    assert len(learned) == 1, rep["terms"]
    assert fs.LAW_OF[learned[0]["dependences"][0]] == "spring"
    assert any(c in learned[0]["dependences"] for c in fs.CONTACTS)
    cubes = {k: v for k, v in learned[0]["params"].items() if k.startswith(fs.PROGRESSIVE)}
    assert cubes and all(v > 0 for v in cubes.values()), learned[0]["params"]   # stiffer: the truth's cube
    assert "smooth progressive part" in learned[0]["description"]
    # the fit with the cube beside the contact leaves far less than the contact alone did (1.77x in sample)
    assert (f.result_.rss / f.result_.n) ** 0.5 < 1.4


def test_a_recorded_road_that_leads_on_one_axle_is_a_spring_of_that_axle():
    f, rep = _diagnose("gas/polytropic_charge_rear")
    step = f.force_shape_[0]
    assert step["input_led"] and step["dependences"][0] == "road_height"
    assert not f.unmeasured_ and rep["verdict"] == "missing_physics"
    # no reading of the states stable: a spring of the rear offered, named as the learned force
    reading = step["state_reading"]
    assert reading["spring_offered_on_axle"] == "rear" and reading["states_explain_input_silent_drives"]
    learned = [t for t in rep["terms"] if t["name"] == fs.TERM]
    assert len(learned) == 1 and fs.LAW_OF[learned[0]["dependences"][0]] == "spring", rep["terms"]
    assert "rear axle only" in learned[0]["description"]
    assert "on the rear axle only where the drives carry it" in rep["reason"]
    assert "a spring of that axle offered to the fit passed every test" in rep["reason"]
    # on as shipped since the family cases it can reach ran with it (benchmarks/RESULTS.md, 2026-12-01)
    assert fs.settings()["fit.spring_where_road_leads_one_axle"] is True
