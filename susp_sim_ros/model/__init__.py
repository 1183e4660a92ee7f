"""Pure physics core: parameters, friction terms, the compiled five-mass vehicle kernel, maneuvers and
virtual rigs. Imports numpy, numba, pyyaml only; never rclpy."""
from . import extra_terms  # noqa: F401  (registers the library terms by name)
from .layout import OUTPUT_LABELS, WHEELS
from .params import FrictionVariant, VehicleParams, config_dir, load_variant, load_vehicle
from .road import RoadProfile, cosine_bump
from .terms import PhysicsTerm, TermParam, get_term, register_term
from .response import Response
from .vehicle import Model, Stepper, make_inputs, simulate, simulate_batch

__all__ = ["OUTPUT_LABELS", "WHEELS", "FrictionVariant", "VehicleParams", "config_dir", "load_variant",
           "load_vehicle", "RoadProfile", "cosine_bump", "PhysicsTerm", "TermParam", "get_term",
           "register_term", "Model", "Response", "Stepper", "make_inputs", "simulate",
           "simulate_batch"]
