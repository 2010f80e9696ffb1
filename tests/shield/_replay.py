"""What the shield-replay tests share: the CLI runner and the docs' simulator shield
(R2..R6 and the release of ``requirements/shield/release.fret``, Python form) built into a
folder."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

REPO = Path(__file__).resolve().parents[2]
TRACE = REPO / "traces" / "sif_disabled.mcap"


def run(*args: str):
    """``fretc ARGS`` in process (click's result: ``exit_code``, ``output``)."""
    return CliRunner().invoke(main, list(args))


def docs_shield(out: Path) -> Path:
    """``out`` after ``fretc shield`` wrote the docs' simulator shield (Python form) into it."""
    got = run("shield", str(REPO / "requirements" / "safe_ros.fret"),
              str(REPO / "requirements" / "shield" / "release.fret"), "-b",
              str(REPO / "requirements" / "shield" / "safe_ros_shield.bindings.toml"),
              "--inputs", "too_close,scan_stale,clearance,obstacle_ahead,obstacle_behind",
              "--outputs", "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed,"
              "linear_velocity", "--emit", "python", "-o", str(out))
    assert got.exit_code == 0, got.output
    return out


def copy_mcap(src: Path, dst: Path, keep, *, library: str = "", metadata: dict | None = None) -> None:
    """``src`` copied to ``dst`` by the mcap library, the messages ``keep(topic, log_time)``
    refuses left out; ``library`` names the writer (profile ros2) and ``metadata`` is
    ``{name: {key: value}}`` added before the summary."""
    from mcap.reader import make_reader
    from mcap.writer import Writer

    with open(src, "rb") as f, open(dst, "wb") as g:
        w = Writer(g)
        if library:
            w.start(profile="ros2", library=library)
        else:
            w.start()
        schemas, channels = {}, {}
        for schema, channel, m in make_reader(f).iter_messages(log_time_order=True):
            if not keep(channel.topic, m.log_time):
                continue
            if schema.id not in schemas:
                schemas[schema.id] = w.register_schema(schema.name, schema.encoding,
                                                       schema.data)
            if channel.id not in channels:
                channels[channel.id] = w.register_channel(
                    channel.topic, channel.message_encoding, schemas[schema.id],
                    dict(channel.metadata))
            w.add_message(channels[channel.id], m.log_time, m.data, m.publish_time,
                          m.sequence)
        for name, data in (metadata or {}).items():
            w.add_metadata(name, data)
        w.finish()


def rosbag2_copy(src: Path, bag: Path, **writer_options) -> None:
    """The messages of the MCAP ``src`` written as the rosbag2 folder ``bag`` (ROS 2 Jazzy's
    types; ``writer_options`` to rosbags' Writer, e.g. ``storage_plugin``)."""
    from mcap.reader import make_reader
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    with Writer(bag, version=9, **writer_options) as w, open(src, "rb") as f:
        conns = {}
        for schema, channel, m in make_reader(f).iter_messages(log_time_order=True):
            if channel.topic not in conns:
                conns[channel.topic] = w.add_connection(channel.topic, schema.name,
                                                        typestore=store)
            w.write(conns[channel.topic], m.log_time, m.data)


def python_shield(tmp: Path, name: str, requirements: str, bindings: str) -> Path:
    """The folder ``tmp/shield`` of ``fretc shield --emit python`` over ``requirements`` and
    ``bindings`` written as ``tmp/name.fret`` and ``tmp/name.bindings.toml`` (exit 0)."""
    (tmp / f"{name}.fret").write_text(requirements)
    (tmp / f"{name}.bindings.toml").write_text(bindings)
    got = run("shield", str(tmp / f"{name}.fret"), "-b", str(tmp / f"{name}.bindings.toml"),
              "--emit", "python", "-o", str(tmp / "shield"))
    assert got.exit_code == 0, got.output
    return tmp / "shield"
