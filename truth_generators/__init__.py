"""Truth generators: simulators that are NOT the product's model, the yardsticks that whatever estimates or
discovers something (the discrepancy finder, the damper inspection, the road estimate) is measured against.

Kept outside ``susp_sim_ros`` on purpose: the product never imports them (``setup.py`` does not install
this package). Tests and benchmarks import them from the repository root; a study takes one as a plug-in
(``truth_generator: "truth_generators.roc:bump_crossing"`` in a study file, see
:mod:`susp_sim_ros.analysis.inspection.roc`). How to add a generator form: ``docs/architecture.md``.

- :mod:`.independent_sim`: an independent implementation of model-spec sections 1-4 (own integrator,
  damper-curve shape, friction scalings, assumed values; ``docs/independent_sim.md``).
- :mod:`.independent_roads`: its maneuvers and ISO 8608 roads.
- :mod:`.family`: the generator family over the simulator's form options (each hidden effect in several
  forms, every assumed item varied, cars within and beyond the priors), split into development and
  held-out forms in ``family_split.yaml`` before tuning.
- :mod:`.hidden_force`: drives on the product's kernel with a friction element the estimating model
  lacks and its force exposed (model-made truth for the missing-force estimate's mechanics).
- :mod:`.roc`: the plug-in that gives the inspection ROC study its bump crossings from the simulator.
"""
