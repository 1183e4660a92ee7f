"""``susp replay``: play a recorded test drive onto its topics, with ``/clock``.

Messages go out in log-time order at ``--rate`` times real time, each preceded by a ``/clock`` message
carrying its log time; during gaps ``/clock`` keeps ticking every ``--clock-period`` of recording time, so
a node with ``use_sim_time:=true`` steps exactly as far as the recording's time moved. Topics whose
recorded QoS is transient-local (``/road/profile``) are published latched. By default the recording's
``/sim/...`` and ``/diagnostics`` topics are not replayed (they are outputs of a node, not inputs);
``--topics`` selects topics explicitly. ``--loop`` starts over (``/clock`` jumps back; the node
restarts its simulation). A progress bar goes to stderr.

Before anything is published the recording is read and checked: every message to be played must be a
known ROS type and deserialise (a damaged file is a named error, exit 2, not garbage on the wire). By
default, topics of a type this ROS installation does not know are skipped with a warning (as ``ros2
bag play`` does); asking for one with ``--topics`` is an error, and so is an interface topic
(``/vehicle/speed``, ``/imu/data``, ...) recorded with another type or encoding.
``--dry-run`` stops after that check and prints what would be played (no ROS node is created).

The recording may be an MCAP file, a rosbag2 directory or a ``.db3`` file. With ``--topic-map`` the drive
is read through the map (other topic names, fields, units, IMU frame) and its inputs are played on the
interface's topics (``/vehicle/speed``, ``/imu/data``, ...) in SI units and REP-103 axes, as the node
expects them; the recording's other topics are not played then.
"""
from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import math
import os
import sys
import time
from typing import Any

from ..errors import RecordingError, SuspInputError
from ..io import integrity
from ..io.drive import SPEED, STEERING, TOPIC_TYPES, check_topic, drive_from_recording, read_drive, recording_from_drive
from ..io.reader import read_recording
from ..io.topic_map import add_topic_map_argument
from ..progress import progress as make_progress

OUTPUT_PREFIXES = ("/sim/", "/diagnostics", "/clock", "/rosout", "/parameter_events")


def add_arguments(p) -> None:
    p.add_argument("recording", help="test drive to play (MCAP file, rosbag2 directory or .db3)")
    p.add_argument("--rate", type=float, default=1.0, help="playback speed factor (default 1.0)")
    p.add_argument("--loop", action="store_true", help="play again and again until interrupted")
    p.add_argument("--loops", type=int, default=0, help="with --loop: stop after this many plays (0: forever)")
    p.add_argument("--topics", nargs="+", help="replay only these topics")
    p.add_argument("--no-clock", action="store_true", help="do not publish /clock")
    p.add_argument("--clock-period", type=float, default=0.01,
                   help="publish /clock at least every this much recording time [s] (default 0.01)")
    p.add_argument("--wait-subscribers", type=float, default=2.0,
                   help="wait up to this long [s] for a subscriber before playing (default 2)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--dry-run", action="store_true",
                   help="read and check the recording, print what would be played, publish nothing")
    add_topic_map_argument(p)  # then the mapped inputs are played on the interface's topics, converted


def _msg_class(msgtype: str, topic: str = ""):
    try:
        pkg, kind, name = msgtype.split("/")
        if kind != "msg" or not pkg.isidentifier() or not name.isidentifier():
            raise ValueError(msgtype)
        # only a package with a msg/ folder is imported: a schema name never runs arbitrary modules
        spec = importlib.util.find_spec(pkg)
        if spec is None or not spec.submodule_search_locations or not any(
                os.path.isdir(os.path.join(loc, "msg")) for loc in spec.submodule_search_locations):
            raise ImportError(pkg)
        return getattr(importlib.import_module(f"{pkg}.msg"), name)
    except (ValueError, ImportError, AttributeError):
        where = f"topic {topic}: " if topic else ""
        raise RecordingError(f"{where}message type {msgtype!r} is not available in this ROS "
                             f"installation (unknown schema)") from None


def _timeline(msgs, t0: int, t1: int, clock_ns: int):
    """(t_ns, message or None for a clock-only tick) in time order."""
    k = 0
    t_clock = t0
    for m in msgs:
        while clock_ns > 0 and t_clock + clock_ns < m.log_time_ns:
            t_clock += clock_ns
            yield t_clock, None
        yield m.log_time_ns, m
        t_clock = max(t_clock, m.log_time_ns)
        k += 1
    while clock_ns > 0 and t_clock + clock_ns <= t1:
        t_clock += clock_ns
        yield t_clock, None


def _check_integrity(rec, path) -> None:
    """The input integrity check (io/integrity.py) of a recording that holds a test drive; replay plays the
    recording as it is, so each finding is reported with action ``kept``; a defect that leaves nothing sound
    (an IntegrityError: implausible unit, missing road, unusable oil levels) is a named error (exit 2), as in
    every command. Not a drive: nothing to check."""
    if not (rec.by_topic(SPEED) and rec.by_topic(STEERING)):
        return
    try:
        drive = drive_from_recording(rec)
    except integrity.IntegrityError:
        raise  # bad_metadata (damper_oil_level not four fractions): a named error (exit 2), as in every command
    except RecordingError:
        return  # the topics are checked (and named) below as the replay needs them
    res = integrity.check_drive_integrity(drive, str(path))
    integrity.report([dataclasses.replace(f, action="kept", detail=f"{f.detail} (replayed as recorded)")
                      for f in res.findings])


def plan(args):
    """Read and check the recording: ``(recording, topics to play, messages in log-time order)``."""
    if not (math.isfinite(args.rate) and args.rate > 0):
        raise SuspInputError(f"--rate: expected a factor > 0, got {args.rate}")
    if not (math.isfinite(args.clock_period) and args.clock_period > 0):
        raise SuspInputError(f"--clock-period: expected a period > 0 s, got {args.clock_period}")
    if getattr(args, "topic_map", None) is not None:
        # read the drive through the map and play its inputs on the interface's own topics (SI, REP-103)
        rec = recording_from_drive(read_drive(args.recording, topic_map=args.topic_map), args.recording)
    else:
        rec = read_recording(args.recording)
        _check_integrity(rec, args.recording)
    topics = rec.topics()
    skipped: list[str] = []
    if args.topics:
        missing = [t for t in args.topics if t not in topics]
        if missing:
            raise RecordingError(f"{args.recording}: no topic(s) {', '.join(missing)} (topics: "
                                 f"{', '.join(sorted(topics))})")
        play = set(args.topics)
    else:
        play = {t for t in topics if not t.startswith(OUTPUT_PREFIXES)}
        for t in sorted(play & set(TOPIC_TYPES)):  # the interface's topics must have their types
            check_topic(rec, t)
        for t in sorted(play):  # like ros2 bag play: topics of unknown type are skipped, with a warning
            try:
                _msg_class(topics[t] or "(no schema)", t)
            except RecordingError as exc:
                print(f"susp replay: warning: {args.recording}: skipping {exc}", file=sys.stderr)
                play.discard(t)
                skipped.append(t)
    msgs = sorted((m for m in rec.messages if m.topic in play), key=lambda m: m.log_time_ns)
    if not msgs:
        why = f" (file damaged: {rec.error})" if rec.truncated else ""
        raise RecordingError(f"{args.recording}: no messages to replay on "
                             f"{', '.join(sorted(play)) or 'any topic'}{why}")
    _check_messages(args.recording, rec, msgs, {t: topics[t] for t in play})
    args.skipped_topics = skipped
    return rec, play, msgs


def _check_messages(path, rec, msgs, types: dict[str, str]) -> None:
    """Every message must be of a known ROS type and deserialise (RecordingError naming topic and time)."""
    from rclpy.serialization import deserialize_message
    classes = {}
    for topic, msgtype in types.items():
        chans = [c for c in rec.channels.values() if c.topic == topic]
        if any(c.message_encoding != "cdr" for c in chans):
            raise RecordingError(f"{path}: topic {topic}: message encoding "
                                 f"{chans[0].message_encoding!r} cannot be replayed (expected cdr)")
        classes[topic] = _msg_class(msgtype or "(no schema)", topic)
    for m in msgs:
        try:
            deserialize_message(m.data, classes[m.topic])
        except Exception as exc:  # rclpy raises assorted errors on malformed CDR
            raise RecordingError(f"{path}: topic {m.topic}: the {m.msgtype} message at log time "
                                 f"{m.log_time_ns} ns does not deserialise ({type(exc).__name__}: {exc})") from None


HANDSHAKE_MIN_S = 5.0  # the first instant's acknowledgement is awaited at least this long [s]


def _delivered(publishers, timeout_s: float) -> bool:
    """Whether every reliable subscriber acknowledged what ``publishers`` sent, waiting up to ``timeout_s``.

    A publisher sees a subscription as soon as *it* has discovered it, but the subscriber drops data from a
    writer it has not discovered yet; a loaded host can take longer than any fixed pause for that, and a
    10x replay is over by then (the subscriber then gets only the writer's history, the last 100 messages).
    An acknowledgement comes only from a subscriber that has matched this writer, so waiting for it after
    the first instant makes the start of the recording reach every subscriber."""
    from rclpy.duration import Duration
    end = time.monotonic() + timeout_s
    return all(p.wait_for_all_acked(Duration(nanoseconds=int(max(end - time.monotonic(), 0.0) * 1e9)))
               for p in publishers)


def _dry_run(args, rec, play, msgs) -> dict:
    """What a replay would play (``--dry-run``): messages per topic, duration, the file's state."""
    t0, t1 = msgs[0].log_time_ns, msgs[-1].log_time_ns
    counts = {t: sum(1 for m in msgs if m.topic == t) for t in sorted(play)}
    return {"recording": str(args.recording), "dry_run": True, "messages": len(msgs),
            "topics": sorted(play), "skipped_topics": args.skipped_topics, "counts": counts,
            "duration_s": (t1 - t0) * 1e-9,
            "truncated": rec.truncated, "finalised": rec.finalised,
            "summary": f"would replay {len(msgs)} messages on {len(play)} topics from {args.recording} "
                       f"({(t1 - t0) * 1e-9:.2f} s of recording"
                       + (f"; file truncated: {rec.error}" if rec.truncated else "") + ")"}


@dataclasses.dataclass(frozen=True)
class _Player:
    """What one play of a recording sends, where to and how fast."""

    recording: str           #: the recording's path as given (for messages)
    msgs: list               #: messages to play, in log-time order
    pubs: dict               #: topic -> its publisher
    clock_pub: Any           #: the ``/clock`` publisher, or None (``--no-clock``)
    clock_type: type         #: rosgraph_msgs' Clock (imported with rclpy by the caller)
    clock_ns: int            #: ``/clock`` ticks at least this often in recording time [ns]; 0: none
    rate: float              #: playback speed over real time [-]


def _play_once(player: _Player, progress, handshake) -> int:
    """Play the recording once at ``player.rate``, one ``/clock`` per instant (if ``player.clock_pub``);
    returns the number of messages published. ``handshake`` (publishers, deadline) on the first play: the
    clock starts once every subscriber has acknowledged the first instant."""
    msgs, rate, clock_pub = player.msgs, player.rate, player.clock_pub
    t0, t1 = msgs[0].log_time_ns, msgs[-1].log_time_ns
    played = 0
    start = time.monotonic()
    last_shown = t0
    t_sent = None
    for t, m in _timeline(msgs, t0, t1, player.clock_ns):
        if handshake is not None and t_sent is not None and t != t_sent:
            # the first instant is out: the clock starts once every subscriber has it
            everything, deadline = handshake
            handshake = None
            if not _delivered(everything, max(deadline - time.monotonic(), HANDSHAKE_MIN_S)):
                print(f"susp replay: warning: the first messages of {player.recording} were not "
                      "acknowledged by every subscriber; a slow subscriber may miss the start",
                      file=sys.stderr)
            start = time.monotonic() - (t_sent - t0) * 1e-9 / rate
        wait = start + (t - t0) * 1e-9 / rate - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        if clock_pub is not None and t != t_sent:  # one /clock per instant
            t_sent = t
            c = player.clock_type()
            c.clock.sec, c.clock.nanosec = divmod(t, 1_000_000_000)
            clock_pub.publish(c)
        if m is not None:
            player.pubs[m.topic].publish(m.data)
            played += 1
        if progress is not None and t - last_shown >= 100_000_000:
            progress.update(round((t - last_shown) * 1e-9, 2))
            last_shown = t
    if progress is not None:
        progress.update(round((t1 - last_shown) * 1e-9, 2))
    return played


def _publishers(node, rec, play, clock_type: type, with_clock: bool) -> tuple[dict, Any]:
    """A publisher per topic to play, with the QoS the node subscribes with (transient-local for a
    latched topic such as the road profile), and the ``/clock`` publisher (None without)."""
    # function-level: ros.qos imports rclpy; `susp --help` and `--dry-run` must not (optional ROS dependency)
    from ..ros.qos import INPUT_QOS, LATCHED_QOS  # the profiles the node subscribes with

    topics = rec.topics()
    pubs = {}
    for topic in sorted(play):
        qos = LATCHED_QOS if rec.latched(topic) else INPUT_QOS
        pubs[topic] = node.create_publisher(_msg_class(topics[topic], topic), topic, qos)
    clock_pub = node.create_publisher(clock_type, "/clock", 100) if with_clock else None
    return pubs, clock_pub


def _await_subscribers(everything: list, wait_s: float) -> tuple[float, bool]:
    """Wait up to ``wait_s`` [s] until every publisher has a subscriber, so nothing early is lost to
    discovery; returns (the deadline on the monotonic clock [s], whether any subscriber matched)."""
    deadline = time.monotonic() + wait_s
    while time.monotonic() < deadline and not all(p.get_subscription_count() for p in everything):
        time.sleep(0.02)
    handshake = any(p.get_subscription_count() for p in everything)
    if handshake:
        time.sleep(0.2)  # matched: give the subscribers' side of discovery a moment
    return deadline, handshake


def run(args) -> dict:
    """Play the recording onto its topics (with ``/clock``), in real time times ``--rate``; with
    ``--dry-run`` only say what would be played (no rclpy)."""
    rec, play, msgs = plan(args)
    t0, t1 = msgs[0].log_time_ns, msgs[-1].log_time_ns
    if args.dry_run:
        return _dry_run(args, rec, play, msgs)

    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rosgraph_msgs.msg import Clock

    rclpy.init(args=["--ros-args"])
    node = rclpy.create_node("susp_replay")
    pubs, clock_pub = _publishers(node, rec, play, Clock, with_clock=not args.no_clock)
    everything = list(pubs.values()) + ([clock_pub] if clock_pub is not None else [])
    deadline, handshake = _await_subscribers(everything, args.wait_subscribers)
    progress = None
    if not args.no_progress:
        progress = make_progress(total=round((t1 - t0) * 1e-9, 2), unit="s", desc="replay",
                                 bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} s [{elapsed}<{remaining}]")
    played = loops = 0
    clock_ns = int(round(args.clock_period * 1e9)) if clock_pub is not None else 0
    player = _Player(args.recording, msgs, pubs, clock_pub, Clock, clock_ns, args.rate)
    wall0 = time.monotonic()
    interrupted = False
    try:
        while True:
            played += _play_once(player, progress, (everything, deadline) if handshake else None)
            handshake = False
            loops += 1
            if not args.loop or (args.loops and loops >= args.loops):
                break
            if progress is not None:
                progress.reset()
    except (KeyboardInterrupt, ExternalShutdownException):
        interrupted = True
    finally:
        if progress is not None:
            progress.close()
        time.sleep(0.2)  # let the last messages leave
        node.destroy_node()
        rclpy.try_shutdown()
    wall = time.monotonic() - wall0
    return {"recording": str(args.recording), "messages": played, "loops": loops, "rate": args.rate,
            "topics": sorted(play), "skipped_topics": args.skipped_topics, "duration_s": (t1 - t0) * 1e-9,
            "wall_s": wall,
            "interrupted": interrupted,
            "summary": f"replayed {played} messages on {len(play)} topics from {args.recording} "
                       f"({loops} play(s), rate {args.rate:g}x, {wall:.1f} s)"}
