"""``susp import-csv``: convert a CSV measurement (plus an optional road-profile CSV) into a recorded test
drive MCAP. The CSV layout is documented in :mod:`susp_sim_ros.analysis.csv_import`; every malformed line
or missing column is an error naming the file, the line and the column (exit 2)."""
from __future__ import annotations

from ..analysis.csv_import import import_csv


def add_arguments(p) -> None:
    p.add_argument("drive_csv", help="drive CSV: time_s, steering_wheel_angle_rad|_deg, speed_m_s|_km_h, "
                                     "roll/pitch/yaw_rate_rad_s|_deg_s [, accel_x/y/z_m_s2] "
                                     "[, wheel_height_fl/fr/rl/rr_m]")
    p.add_argument("--road", default=None, help="road-profile CSV: s_m, z_left_m, z_right_m (default: flat road)")
    p.add_argument("--out", required=True, help="output MCAP (refuses to overwrite without --overwrite)")
    p.add_argument("--vehicle", default="passat_b8_like", help="vehicle parameter set name (metadata)")
    p.add_argument("--maneuver", default="", help="maneuver text, e.g. bump_crossing_8kmh or sine_steer_50kmh")
    p.add_argument("--oil", default="1,1,1,1", help="damper oil levels FL,FR,RL,RR in [0, 1]")
    p.add_argument("--source", default="measured", help="metadata source (default: measured)")
    p.add_argument("--notes", default="", help="free text kept in the metadata")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")


def run(args) -> dict:
    res = import_csv(args.drive_csv, args.out, args.road, overwrite=args.overwrite, vehicle=args.vehicle,
                     maneuver=args.maneuver, damper_oil_level=args.oil, source=args.source, notes=args.notes)
    res["summary"] = (f"{args.drive_csv} -> {res['out']}: {res['samples']} samples over {res['duration_s']:.2f} s, "
                      f"{res['messages']} messages" + (f", road profile of {res['road_samples']} points"
                                                       if res["road_samples"] else ", flat road"))
    return res
