"""Reference semi-active damper controllers (pure; no rclpy): :mod:`.controllers` maps measured body
and suspension states to a valve command per corner, :mod:`.ride` drives the car over a random road
with a controller in the loop and reports the ride metrics."""
from .controllers import CONTROLLERS, ControllerParams, Measurement, load_controller_params, make_controller

__all__ = ["CONTROLLERS", "ControllerParams", "Measurement", "load_controller_params", "make_controller"]
