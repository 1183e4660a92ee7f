"""``susp import-csv``: convert a CSV measurement (plus an optional road-profile CSV) into a recorded test
drive MCAP. The CSV layout is documented in :mod:`susp_sim_ros.analysis.csv_import`; every malformed line
or missing column is an error naming the file, the line and the column (exit 2)."""
from __future__ import annotations

from ..analysis.csv_import import import_csv
from .import_measurement import add_output_arguments


def add_arguments(p) -> None:
    p.add_argument("drive_csv", help="drive CSV: time_s, steering_wheel_angle_rad|_deg, speed_m_s|_km_h, "
                                     "roll/pitch/yaw_rate_rad_s|_deg_s [, accel_x/y/z_m_s2] "
                                     "[, wheel_height_fl/fr/rl/rr_m]")
    p.add_argument("--road", default=None, help="road-profile CSV: s_m, z_left_m, z_right_m (default: flat road)")
    add_output_arguments(p)


def run(args) -> dict:
    res = import_csv(args.drive_csv, args.out, args.road, overwrite=args.overwrite, vehicle=args.vehicle,
                     maneuver=args.maneuver, damper_oil_level=args.oil, source=args.source, notes=args.notes)
    res["summary"] = (f"{args.drive_csv} -> {res['out']}: {res['samples']} samples over {res['duration_s']:.2f} s, "
                      f"{res['messages']} messages" + (f", road profile of {res['road_samples']} points"
                                                       if res["road_samples"] else ", flat road"))
    return res
