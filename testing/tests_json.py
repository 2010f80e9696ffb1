"""``tests.json`` as ``fretc testgen`` writes it and ``fretc testrun`` (and the pytest file)
reads it: its JSON Schema (:data:`SCHEMA`), checked on read by :func:`load_tests` (every
refusal names the JSON path, as ``$.tests[3].covers``), and the one way a test id becomes a
file name (:func:`file_name`). Nothing a ``tests.json`` holds names a file outside the test
folder or its run folder: ids are single file names, traces are relative paths inside the
folder (the format: :mod:`fretc.cli.testgen`'s docstring)."""

from __future__ import annotations

import json
from pathlib import Path, PurePosixPath, PureWindowsPath
from typing import Any

from fretc.common.errors import InputError

__all__ = ["SCHEMA", "MAX_NAME_BYTES", "TestsJsonError", "load_tests", "file_name"]

#: the longest test id used in a file name, in UTF-8 bytes: file systems allow 255 bytes a
#: name, and the run adds suffixes (``.audit.json``)
MAX_NAME_BYTES = 200

_STRING = {"type": "string", "minLength": 1}
_OBLIGATION = {"type": "object", "required": ["requirement", "obligation"],
               "properties": {"requirement": _STRING, "obligation": _STRING,
                              "tick": {"type": ["integer", "null"]}}}

#: the JSON Schema (2020-12) of ``tests.json``: what testrun reads of it (other members, as
#: ``obligations`` and ``unmeetable``, are testgen's report and not read)
SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "type": "object",
    "required": ["requirements", "tests"],
    "properties": {
        "requirements": {"type": "array", "minItems": 1, "items": _STRING},
        "bindings": {"type": ["string", "null"]},
        "tests": {"type": "array", "items": {
            "type": "object",
            "required": ["id", "trace", "covers", "generated_for"],
            "properties": {
                "id": _STRING,
                "trace": _STRING,
                "ticks": {"type": "integer", "minimum": 0},
                "generated_for": {"anyOf": [_OBLIGATION, {"type": "null"}]},
                "covers": {"type": "array", "items": _OBLIGATION},
                "expected": {"type": "object", "additionalProperties": {"type": "string"}},
            }}},
    },
}


class TestsJsonError(InputError):
    """A ``tests.json`` that testrun cannot use; the message names the file and the JSON
    path."""

    __test__ = False  # not a pytest test class


def file_name(test_id: str, suffix: str = "") -> str:
    """``test_id`` + ``suffix`` as a file name inside a folder: the id itself, never a path.

    Raises:
        ValueError: an id that is empty, ``.`` or ``..``, holds a path separator (``/``,
            ``\\``), a NUL or another control character, is an absolute path, or is longer
            than :data:`MAX_NAME_BYTES` bytes (UTF-8) - it would name another file than
            one in the folder."""
    why = None
    if not isinstance(test_id, str) or test_id in ("", ".", ".."):
        why = "is not a file name"
    elif any(c in test_id for c in "/\\") or PureWindowsPath(test_id).drive:
        why = "holds a path separator"
    elif any(ord(c) < 32 or ord(c) == 127 for c in test_id):
        why = "holds a NUL or another control character"
    elif len(test_id.encode("utf-8", "surrogatepass")) > MAX_NAME_BYTES:
        why = f"is longer than {MAX_NAME_BYTES} bytes"
    if why is not None:
        raise ValueError(f"the test id {test_id!r:.80} {why}: ids become file names in the "
                         "run folder")
    return test_id + suffix


def _trace_problem(trace: str) -> str | None:
    """Why ``trace`` (a test's trace, relative to the test folder) names no file inside the
    folder, or None."""
    p = PurePosixPath(trace)
    if p.is_absolute() or PureWindowsPath(trace).drive or PureWindowsPath(trace).root:
        return "is an absolute path"
    if ".." in p.parts or "\\" in trace:
        return "leaves the test folder"
    if "\x00" in trace:
        return "holds a NUL"
    return None


def _where(error: Any) -> str:
    """A schema error as ``$.path: what``: a missing member is named by its own path
    (``$.tests[0].covers: missing``); a value by its path and the rule it breaks."""
    if error.validator == "required":
        gone = [k for k in error.validator_value if k not in error.instance]
        if gone:
            return f"{error.json_path}.{gone[0]}: missing"
    value = repr(error.instance)
    value = value if len(value) <= 60 else value[:57] + "..."
    rule = {"type": f"is not of type {error.validator_value!r}",
            "minItems": f"has fewer than {error.validator_value} items",
            "minLength": "is empty", "minimum": f"is less than {error.validator_value}",
            "anyOf": "is neither an object with requirement and obligation nor null",
            }.get(error.validator, "breaks the rule " + repr(error.validator))
    return f"{error.json_path}: {value} {rule}"


def load_tests(folder: str | Path) -> dict[str, Any]:
    """``folder/tests.json`` read and checked (module docstring).

    Raises:
        TestsJsonError: unreadable, not JSON (or nested too deeply), not valid under
            :data:`SCHEMA` (the first error in document order, by its JSON path), a test id
            that is not a file name (:func:`file_name`), two tests with one id, or a trace
            outside the folder."""
    import jsonschema  # lazy: only where tests.json is read

    path = Path(folder) / "tests.json"
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise TestsJsonError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise TestsJsonError(f"{path}: not JSON: {exc}") from None
    except RecursionError:
        raise TestsJsonError(f"{path}: not a tests.json of fretc testgen: JSON nested too "
                             "deeply") from None
    try:
        errors = sorted(jsonschema.Draft202012Validator(SCHEMA).iter_errors(doc),
                        key=lambda e: [str(p) for p in e.absolute_path])
    except RecursionError:
        raise TestsJsonError(f"{path}: not a tests.json of fretc testgen: JSON nested too "
                             "deeply") from None
    if errors:
        raise TestsJsonError(f"{path}: {_where(errors[0])} (not a tests.json of fretc "
                             "testgen)")
    seen: set[str] = set()
    for i, t in enumerate(doc["tests"]):
        try:
            file_name(t["id"])
        except ValueError as exc:
            raise TestsJsonError(f"{path}: $.tests[{i}].id: {exc}") from None
        if t["id"] in seen:
            raise TestsJsonError(f"{path}: $.tests[{i}].id: {t['id']!r} is the id of an "
                                 "earlier test too")
        seen.add(t["id"])
        why = _trace_problem(t["trace"])
        if why is not None:
            raise TestsJsonError(f"{path}: $.tests[{i}].trace: {t['trace']!r:.80} {why}")
    return dict(doc)  # an object: the schema says so
