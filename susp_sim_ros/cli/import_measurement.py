"""``susp import``: a measurement (ASAM MDF4 ``.mf4`` or CSV) plus an optional road (OpenCRG ``.crg`` or CSV)
into a recorded test drive MCAP (interface.md). Channel maps, units, frames and the road sampling are
documented in :mod:`susp_sim_ros.analysis.measurement_import`; what was converted is kept in the
``test_drive`` metadata. ``susp import-csv`` is the CSV-only form of the same import (kept as an alias).
Bad input (unknown channel, unit, malformed map, unreadable file) is an error naming it, exit 2."""
from __future__ import annotations

from ..analysis.measurement_import import import_measurement
from ..model.paper import MANEUVER_KINDS
from ..model.params import DEFAULT_VEHICLE


def add_arguments(p) -> None:
    p.add_argument("drive", metavar="DRIVE.mf4|.csv", help="measurement: ASAM MDF4 (.mf4/.mdf) or CSV")
    p.add_argument("--channel-map", "--topic-map", dest="channel_map", metavar="MAP.yaml", default=None,
                   help="MDF4 channel map: channel name, unit/scale per input and the IMU frame (default: "
                        "channels named as the CSV columns, REP-103 axes)")
    p.add_argument("--road", default=None, metavar="ROAD.crg|.csv",
                   help="road: OpenCRG file (wheel tracks at +-track/2) or road CSV (default: flat road)")
    p.add_argument("--road-start-u", type=float, default=None, metavar="U",
                   help="OpenCRG u [m] under the front axle when the drive starts (default: the road's first u)")
    add_output_arguments(p)


def add_output_arguments(p) -> None:
    """The output file and the ``test_drive`` metadata of an import (``susp import``, ``susp import-csv``)."""
    p.add_argument("--out", required=True, help="output MCAP (refuses to overwrite without --overwrite)")
    p.add_argument("--vehicle", default=DEFAULT_VEHICLE, help="vehicle parameter set name (metadata; with an "
                                                               "OpenCRG road its front track places the wheel "
                                                               "tracks)")
    p.add_argument("--maneuver", default="", help="maneuver text, e.g. "
                   + " or ".join(k.label for k in MANEUVER_KINDS.values()))
    p.add_argument("--oil", default="1,1,1,1", help="damper oil levels FL,FR,RL,RR in [0, 1]")
    p.add_argument("--source", default="measured", help="metadata source (default: measured)")
    p.add_argument("--notes", default="", help="free text kept in the metadata")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")


def run(args) -> dict:
    res = import_measurement(args.drive, args.out, args.road, channel_map=args.channel_map,
                             overwrite=args.overwrite, vehicle=args.vehicle, road_start_u=args.road_start_u,
                             maneuver=args.maneuver,
                             damper_oil_level=args.oil, source=args.source, notes=args.notes)
    res["summary"] = (f"{args.drive} -> {res['out']}: {res['samples']} IMU samples over {res['duration_s']:.2f} s, "
                      f"{res['messages']} messages" + (f", road profile of {res['road_samples']} points"
                                                       if res["road_samples"] else ", flat road"))
    return res
