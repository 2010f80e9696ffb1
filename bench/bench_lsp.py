"""Latency of ``fretc lsp``: the time from an edit to its diagnostics, on a workspace of
requirement files.

Usage::

    python bench/bench_lsp.py [--requirements 1000] [--files 4] [--edits 60]

The workspace (a temporary folder): ``--files`` requirement files of ``--requirements``
requirements in all (Safe-ROS-like sentences with deadlines, comparisons and named variables)
and a bindings file binding every variable. A ``python -m fretc lsp`` process is started and
initialized on it, the first file (``--requirements / --files`` requirements, or all of them
with ``--files 1``) is opened, and then ``--edits`` edits are sent one at a time, each as
an editor sends it (``didChange`` with the whole text): a character typed inside a
requirement in the middle of the document, and one edit in four a new line at its top
(moving every requirement). For each edit the time from writing the ``didChange`` to
reading the ``publishDiagnostics`` of that version is taken; printed: the median, the 95th
percentile and the largest, and, as the baseline measured in the same run on the same
text, the median time of one analysis of the document without the session's memory (what
every keystroke cost before the analysis kept its parsed sentences), and their ratio.

The goal: every edit's diagnostics within 100 ms at 1,000 requirements.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))

from fuzz_lsp import RawClient  # noqa: E402


def workspace(folder: Path, n: int, files: int) -> list[Path]:
    """Write the workspace (module docstring); its requirement files."""
    per = max(1, n // files)
    out = []
    for f in range(files):
        lines = ["@tick_period 100 ms"]
        for i in range(f * per, (f + 1) * per):
            lines.append(f"R{i}: upon too_close{i % 9} robot shall within {i % 7 + 1} "
                         f"seconds satisfy stopped{i % 5} & speed{i % 11} < {i % 3 + 1}")
            if i % 10 == 1:
                lines.append(f"    parent: R{i - 1}")
        p = folder / f"part{f}.fret"
        p.write_text("\n".join(lines) + "\n")
        out.append(p)
    bind = ['[tick]', 'period = "100 ms"', '[variables]']
    bind += [f'too_close{k} = "min(/scan{k}.ranges) < 0.9"' for k in range(9)]
    bind += [f'stopped{k} = "abs(/cmd{k}.linear.x) < 1e-3"' for k in range(5)]
    bind += [f'speed{k} = "abs(/cmd{k % 5}.linear.x)"' for k in range(11)]
    (folder / "robot.bindings.toml").write_text("\n".join(bind) + "\n")
    return out


def _wait_diagnostics(client: RawClient, uri: str, version: int, bound: float = 60.0):
    end = time.monotonic() + bound
    while time.monotonic() < end:
        try:
            m = client.messages.get(timeout=max(0.001, end - time.monotonic()))
        except Exception:  # noqa: BLE001 - queue.Empty: past the bound
            break
        if m.get("method") == "textDocument/publishDiagnostics" and \
                m["params"]["uri"] == uri and m["params"].get("version") == version:
            return m
    raise SystemExit(f"no diagnostics of version {version} within {bound} s")


def baseline(text: str, path: str, runs: int = 5) -> float:
    """Median seconds of one analysis without a session's memory."""
    from fretc.editor.document import analyse

    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        analyse(text, path)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--requirements", type=int, default=1000)
    ap.add_argument("--files", type=int, default=1)
    ap.add_argument("--edits", type=int, default=60)
    args = ap.parse_args(argv)
    folder = Path(tempfile.mkdtemp(prefix="fretc_bench_lsp_"))
    files = workspace(folder, args.requirements, args.files)
    doc = files[0]
    text = doc.read_text()
    client = RawClient(folder)
    client.request("initialize", {"processId": None, "rootUri": folder.as_uri(),
                                  "capabilities": {}}, bound=120)
    client.notify("initialized", {})
    uri = doc.as_uri()
    t0 = time.perf_counter()
    client.notify("textDocument/didOpen", {"textDocument": {
        "uri": uri, "languageId": "fretish", "version": 1, "text": text}})
    _wait_diagnostics(client, uri, 1)
    first = time.perf_counter() - t0
    lines = text.split("\n")
    mid = len(lines) // 2
    latencies = []
    for k in range(args.edits):
        version = k + 2
        if k % 4 == 3:
            lines.insert(1, f"# note {k}")
            mid += 1
        else:
            lines[mid] = lines[mid].replace(" robot ", " robot" + " " * (k % 3 + 1), 1) \
                if k % 2 else lines[mid].replace("robot  ", "robot ", 1)
        new = "\n".join(lines)
        t0 = time.perf_counter()
        client.notify("textDocument/didChange", {"textDocument": {"uri": uri,
                                                                  "version": version},
                                                 "contentChanges": [{"text": new}]})
        _wait_diagnostics(client, uri, version)
        latencies.append(time.perf_counter() - t0)
    client.close()
    base = baseline(text, str(doc))
    lat = sorted(latencies)
    med = statistics.median(lat)
    out = {"requirements_in_document": text.count("\nR"), "workspace_requirements":
           args.requirements, "edits": len(lat), "open_s": round(first, 3),
           "edit_median_ms": round(1000 * med, 1),
           "edit_p95_ms": round(1000 * lat[int(0.95 * (len(lat) - 1))], 1),
           "edit_max_ms": round(1000 * lat[-1], 1),
           "baseline_full_analysis_ms": round(1000 * base, 1),
           "ratio_edit_to_full_analysis": round(med / base, 3),
           "within_100_ms": lat[-1] <= 0.1}
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
