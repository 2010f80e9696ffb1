"""``fretc shield --emit ros2``: the shield as a ROS 2 Python package (ament_python) with one
node, the Safety System of Safe-ROS generated: the SIF's stop request and the
``cmd_vel_interceptor``'s forwarding, corrected by the shield.

The package ``<name>_shield_ros2`` (``colcon build``, or ``python -m <name>_shield_ros2``
with rclpy and fretc) holds the generated Python shield, the binding file and the node
(:func:`node_source`), which subscribes the input and proposal topics, ticks on the
``[shield] tick`` topic and its timer, and publishes the corrected outputs
(:class:`fretc.shield.messages.MessageShield`) and ``/diagnostics``; it meets every
``within`` deadline :func:`node_margin` ticks early (``[shield] latency_budget``, default
:data:`LATENCY_BUDGET`). The node's subscriptions, ticks, messages and timing in full:
ARCHITECTURE.md ("The ROS 2 node").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any

from fretc.common.textsafe import python_doc, xml_content
from fretc.shield.build import Shield
from fretc.shield.emit_python import render_python, tables
from fretc.shield.messages import proposals_of
from fretc.shield.plan import ShieldError
from fretc.shield.runtime_values import term_variables
from fretc.signals.bindings.spec import Bindings

__all__ = ["render_ros2", "node_source", "node_margin", "latency_budget", "LATENCY_BUDGET",
           "proposal_timeout", "PROPOSAL_TIMEOUT_TICKS"]

#: the node's latency budget (s) without ``[shield] latency_budget``: about ten times what
#: bench/bench_ros2.py measures for the node's own work on this machine (p99 3 ms from the
#: scan's publication to the command's arrival, the node's part about 1.2 ms at p50)
LATENCY_BUDGET = Fraction(1, 50)

#: the node's proposal timeout without ``[shield] proposal_timeout``, in tick periods: 300 ms
#: at 100 ms (six periods of a 20 Hz controller, three of a 10 Hz one); a proposal older is
#: absent and the fallback is published
PROPOSAL_TIMEOUT_TICKS = 3


def node_margin(period: Fraction, budget: Fraction = LATENCY_BUDGET) -> int:
    """The ticks early the node meets each ``within`` deadline (module docstring): the
    sampling phase (a whole period) and the latency ``budget`` (s), in ticks of ``period``
    (s), rounded up."""
    return math.ceil((period + budget) / period)


def proposal_timeout(bindings_file: str | None) -> Fraction | None:
    """``[shield] proposal_timeout`` of the binding file (a duration, ``"300 ms"``), else
    None (the node's default: :data:`PROPOSAL_TIMEOUT_TICKS` tick periods).

    Raises:
        ShieldError: not a duration, or not positive."""
    return _shield_duration(bindings_file, "proposal_timeout", "300 ms")


def latency_budget(bindings_file: str | None) -> Fraction:
    """``[shield] latency_budget`` of the binding file (a duration, ``"20 ms"``), else
    :data:`LATENCY_BUDGET`.

    Raises:
        ShieldError: not a duration, or not positive."""
    budget = _shield_duration(bindings_file, "latency_budget", "20 ms")
    return LATENCY_BUDGET if budget is None else budget


def _shield_duration(bindings_file: str | None, key: str, example: str) -> Fraction | None:
    """``[shield] key`` of the binding file in seconds, None when absent. Raises
    :class:`ShieldError` when it is not a positive duration."""
    if bindings_file is None:
        return None
    text = _shield_table(bindings_file).get(key)
    if text is None:
        return None
    from fretc.common.units import parse_duration

    try:
        ns = parse_duration(text) if isinstance(text, str) else None
    except ValueError:
        ns = None
    if ns is None or ns <= 0:
        raise ShieldError(f"{bindings_file}: [shield] {key} must be a positive duration "
                          f"(\"{example}\"), not {text!r}")
    return Fraction(int(ns), 10**9)


def _shield_table(bindings_file: str) -> dict[str, Any]:
    import tomllib

    doc = tomllib.loads(Path(bindings_file).read_text(encoding="utf-8"))
    table = doc.get("shield", {})
    return table if isinstance(table, dict) else {}


def _types(table: dict[str, Any], bindings_file: str) -> dict[str, str]:
    """``[shield] types``: topic -> ``pkg/msg/Type`` (the ROS 2 types the node reads and
    writes; a binding file's ``[types]`` counts too).

    Raises:
        ShieldError: not a table of topic names and type names."""
    types = table.get("types", {})
    if not isinstance(types, dict) or not all(
            isinstance(k, str) and isinstance(v, str) and k.startswith("/") and v.count("/") == 2
            for k, v in types.items()):
        raise ShieldError(f"{bindings_file}: [shield] types must map topics to ROS 2 types, "
                          "e.g. { \"/scan\" = \"sensor_msgs/msg/LaserScan\" }")
    return dict(types)


def _check_types(types: dict[str, str], bindings: Bindings, bindings_file: str) -> None:
    """Every type of ``types`` (topic -> ``pkg/msg/Type``) is one the node can decode and
    make: ROS 2 Jazzy's standard types (rosbags), or those of the binding file's ``[types]
    msg_path`` folders, as the node's type store holds them.

    Raises:
        ShieldError: a type it does not hold, named with its topic."""
    if bindings.msg_path:
        from fretc.logs.ros.msg_path import msg_path_typestore

        store = msg_path_typestore(bindings.msg_path)
    else:
        from rosbags.typesys import Stores, get_typestore

        store = get_typestore(Stores.ROS2_JAZZY)
    unknown = [f"{t} ({name})" for t, name in types.items() if name not in store.types]
    if unknown:
        raise ShieldError(f"{bindings_file}: no ROS 2 message type of that name for "
                          + ", ".join(unknown) + ": the node can decode and make only ROS 2 "
                          "Jazzy's standard types and those of [types] msg_path (give the "
                          "folder of its .msg file there)")


def _topics(shield: Shield, bindings: Bindings, proposals: dict[str, str]
            ) -> tuple[list[str], list[str]]:
    """(topics the inputs read, topics the outputs are published on)."""
    t = tables(shield)
    read = {v for m in t["machines"] for s in m["inputs"]
            for v in (term_variables(s[2]) if s[1] == "pred" else {s[0]})}
    read |= {v for m in t["machines"] for b in m["bounds"]
             for v in term_variables(m["outputs"][b["atom"]][2]) if v != b["variable"]}
    inputs = sorted({topic for v in read for topic in bindings.variables[v].topics})
    outputs = list(dict.fromkeys(topic for m in t["machines"] for g in m["groups"]
                                 for topic in g["topics"]))
    return inputs, outputs


def node_source(pkg: str, module: str, bindings_name: str, types: dict[str, str],
                inputs: list[str], proposals: dict[str, str], outputs: list[str],
                period_ns: int, tick: str | None, margin: int = 0,
                budget_ns: int = 0, proposal_timeout_ns: int | None = None) -> str:
    """The node's Python source (module docstring; ``templates/shield_node.py.j2``):
    ``margin`` the ticks early its shield meets each deadline, ``budget_ns`` its latency
    budget, ``proposal_timeout_ns`` the age (ns) past which a proposal is absent (default
    :data:`PROPOSAL_TIMEOUT_TICKS` periods)."""
    from fretc.compiler.codegen import _env  # lazy: Jinja2 only when the form is written

    if proposal_timeout_ns is None:
        proposal_timeout_ns = PROPOSAL_TIMEOUT_TICKS * period_ns
    return str(_env().get_template("shield_node.py.j2").render(
        pkg=pkg, module=module, bindings_name=bindings_name, types=types, inputs=inputs,
        proposals=proposals, outputs=outputs, period_ns=period_ns, tick=tick, margin=margin,
        budget_ns=budget_ns, proposal_timeout_ns=proposal_timeout_ns))


def render_ros2(shield: Shield, base: str, bindings: Bindings | None,
                bindings_file: str | None, margin: int = 0) -> dict[str, str]:
    """``{relative path: text}`` of the package (module docstring); ``shield`` the node's
    (deadlines ``margin`` ticks early: :func:`node_margin`, made by the caller).

    Raises:
        ShieldError: no binding file, a topic without a type in its ``[types]`` or with a
            type that does not exist (:func:`_check_types`), no proposal topic for an
            output topic, or comparisons of several output variables
            (their corrected numbers have no message the bindings' inversion writes; a
            bound of one output by the inputs is written through the output's binding)."""
    preds = [a.text for m in shield.machines for j, a in enumerate(m.outputs)
             if a.op == "pred" and j not in {b["atom"] for b in m.bounds}]
    if preds:
        raise ShieldError("--emit ros2 cannot publish the outputs of " + ", ".join(preds)
                          + ": a comparison of several output variables is corrected by "
                          "setting their numbers together, which the bindings' inversion "
                          "(one message per valuation of one variable's atoms) does not "
                          "write; use --emit python or c")
    if bindings is None or bindings_file is None:
        raise ShieldError("--emit ros2 needs the binding file (-b): the node reads and writes "
                          "the bound topics")
    proposals = proposals_of(bindings_file)
    inputs, outputs = _topics(shield, bindings, proposals)
    needed = sorted(set(inputs) | set(outputs) | set(proposals.values()))
    table = _shield_table(bindings_file)
    known = {**bindings.types, **_types(table, bindings_file)}
    missing = [t for t in needed if t not in known]
    if missing:
        raise ShieldError(f"{bindings_file}: [shield] types (or [types]) gives no ROS 2 type "
                          f"for {', '.join(missing)} (e.g. \"{missing[0]}\" = "
                          "\"pkg/msg/Type\")")
    tick = table.get("tick")
    if tick is not None and (not isinstance(tick, str) or tick not in known):
        raise ShieldError(f"{bindings_file}: [shield] tick must name a topic whose type is "
                          "given")
    if shield.period is None:
        raise ShieldError("the requirements declare no tick period (@tick_period): the node "
                          "needs one")
    pkg = f"{base}_shield_ros2"
    module = f"{base}_shield"
    types = {t: known[t] for t in needed}
    _check_types(types, bindings, bindings_file)
    period_ns = int(shield.period * 10**9)
    deps = sorted({t.split("/")[0] for t in types.values()}
                  | {"diagnostic_msgs", "rclpy", "std_srvs"})
    budget = latency_budget(bindings_file)
    timeout = proposal_timeout(bindings_file)
    node = node_source(pkg, module, f"{base}.bindings.toml", types, inputs, proposals,
                       outputs, period_ns, tick, margin, int(budget * 10**9),
                       None if timeout is None else int(timeout * 10**9))
    return {
        f"{pkg}/package.xml": _package_xml(pkg, shield, deps),
        f"{pkg}/setup.py": _setup_py(pkg, base),
        f"{pkg}/setup.cfg": f"[develop]\nscript_dir=$base/lib/{pkg}\n[install]\n"
                            f"install_scripts=$base/lib/{pkg}\n",
        f"{pkg}/resource/{pkg}": "",
        f"{pkg}/launch/{pkg}.launch.py": _launch(pkg),
        f"{pkg}/{pkg}/__init__.py": f'"""The shield {python_doc(shield.name)}, generated by '
                                    'fretc shield."""\n',
        f"{pkg}/{pkg}/__main__.py": "from .shield_node import main\n\nmain()\n",
        f"{pkg}/{pkg}/{module}.py": render_python(shield),
        f"{pkg}/{pkg}/{base}.bindings.toml": Path(bindings_file).read_text(encoding="utf-8"),
        f"{pkg}/{pkg}/shield_node.py": node,
    }


def _package_xml(pkg: str, shield: Shield, deps: Sequence[str]) -> str:
    depends = "\n".join(f"  <exec_depend>{d}</exec_depend>" for d in deps)
    return f"""<?xml version="1.0"?>
<?xml-model href="http://download.ros.org/schema/package_format3.xsd" schematypens="http://www.w3.org/2001/XMLSchema"?>
<package format="3">
  <name>{pkg}</name>
  <version>0.1.0</version>
  <description>The shield {xml_content(shield.name)} generated by fretc shield from FRETish requirements
  ({xml_content(", ".join(r.id for r in shield.requirements))}); digest {shield.digest[:16]}. Needs fretc
  (pip install fretc) beside rclpy.</description>
  <maintainer email="nobody@example.com">generated by fretc</maintainer>
  <license>generated</license>
{depends}
  <export>
    <build_type>ament_python</build_type>
  </export>
</package>
"""


def _setup_py(pkg: str, base: str) -> str:
    return f'''from setuptools import setup

package = {pkg!r}

setup(
    name=package,
    version="0.1.0",
    packages=[package],
    package_data={{package: [{base + ".bindings.toml"!r}]}},
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package]),
        ("share/" + package, ["package.xml"]),
        ("share/" + package + "/launch", ["launch/" + package + ".launch.py"]),
    ],
    install_requires=["setuptools", "fretc"],
    zip_safe=True,
    description="A shield generated by fretc shield",
    license="generated",
    entry_points={{"console_scripts": ["shield_node = " + package + ".shield_node:main"]}},
)
'''


def _launch(pkg: str) -> str:
    return f'''"""Launch the shield node: ros2 launch {pkg} {pkg}.launch.py"""

from launch import LaunchDescription
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        Node(package={pkg!r}, executable="shield_node", name={pkg!r}, output="screen"),
    ])
'''
