"""A submitted spec: checked, validated exactly as the CLI validates a file, and frozen in the data directory.

The service runs what a user could run with ``twin campaign run``: the submitted TOML is written to
``input/submitted.toml`` beside copies of the built-in specs (so that ``extends = "demo.toml"`` means
what it means in ``campaigns/specs/``), and ``input/spec.toml`` applies the overrides through the
spec format's own inheritance::

    extends = "submitted.toml"
    root_seed = 7              # only the overrides given
    runs_per_dataset = 2

:func:`campaigns.load_spec` then validates ``input/spec.toml``. Freezing the inputs keeps a queued
or interrupted campaign's spec, and so its hash and its chunk files, whatever happens to the
installation's built-in specs before it resumes.

A spec on a shared server may not reach the server's files: ``extends`` must name a built-in spec,
and scenes and parameter sets must be built-in names, not paths.
"""

from __future__ import annotations

import os
import re
import shutil
import tomllib
import uuid
from dataclasses import dataclass
from pathlib import Path

import campaigns
import twin
from campaigns.runner.spec import CampaignSpec, SpecError, validate_spec
from twin.parameters import available_parameter_sets

BUILTIN_SPECS = Path(campaigns.__file__).parent / "specs"
SUBMITTED_NAME = "submitted.toml"
SPEC_NAME = "spec.toml"
#: What a page-1 figure's file name may look like (:func:`answer_figure_name`): the API serves no other name as one.
ANSWER_FIGURE_NAME = re.compile(r"^detection(_[a-z]+)?\.png$")
#: What a scene or parameter-set name may look like in a submitted spec (no path, no file name).
_BARE_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_-]*$")
#: Deepest nesting of tables and arrays accepted: the built-in specs nest 4 deep; far deeper is an attack on the
#: parser and on everything that walks the spec recursively afterwards (validation, the spec hash's JSON).
MAX_NESTING = 16


def answer_figure_name(key: str) -> str:
    """The file of a fault sweep's answer in a picture, the report's page-1 figure
    (:func:`reports.detection.detection_answer`), which the runner draws beside the results for the campaign page:
    ``detection.png`` for the first sweep, ``detection_preload.png`` for a further preload sweep (``key``: the sweep's
    variable suffix in the analysis, :func:`campaigns.analysis.vocabulary.sweep_key`)."""
    return f"detection{key}.png"


#: The first sweep's figure (the one of a spec with one sweep).
ANSWER_FIGURE = answer_figure_name("")


def builtin_specs() -> list[str]:
    """File names of the specs shipped with BenchTwin (what ``extends`` may name)."""
    return sorted(p.name for p in BUILTIN_SPECS.glob("*.toml"))


@dataclass
class Submission:
    """A validated campaign, its inputs frozen under ``input_dir``."""

    campaign_id: str
    spec: CampaignSpec
    input_dir: Path
    overrides: dict


def input_dir(campaign_dir: Path) -> Path:
    return campaign_dir / "input"


def output_dir(campaign_dir: Path) -> Path:
    return campaign_dir / "out"


def prepare(data: Path, text: str, *, runs: int | None = None, seed: int | None = None,
            check=None) -> Submission:
    """Validate a submitted spec and move its frozen inputs to ``DATA/campaigns/<new id>/input``.

    ``check(spec)`` returns further problems of the validated spec (the service's cost limit), which
    refuse it as well, before anything is kept.

    Raises
    ------
    SpecError
        Listing every problem with its field path; nothing is left in the data directory.
    """
    parsed = _parsed(text)
    problems = _reach_problems(parsed)
    problems += [f"{name}: must be a whole number >= 0, got {value!r}"
                 for name, value in (("runs", runs), ("seed", seed))
                 if value is not None and (not isinstance(value, int) or isinstance(value, bool) or value < 0)]
    if problems:
        raise SpecError(problems + _structural_problems(parsed))
    overrides = {k: v for k, v in (("runs_per_dataset", runs), ("root_seed", seed)) if v is not None}
    staging = data / "staging" / uuid.uuid4().hex
    try:
        staging.mkdir(parents=True)
        for builtin in BUILTIN_SPECS.glob("*.toml"):
            shutil.copyfile(builtin, staging / builtin.name)
        _write(staging / SUBMITTED_NAME, text)
        overlay = f'extends = "{SUBMITTED_NAME}"\n' + "".join(f"{k} = {v}\n" for k, v in overrides.items())
        _write(staging / SPEC_NAME, overlay)
        spec = campaigns.load_spec(staging / SPEC_NAME)
        problems = check(spec) if check is not None else []
        if problems:
            raise SpecError(problems)
        campaign_id = uuid.uuid4().hex[:12]
        final = input_dir(data / "campaigns" / campaign_id)
        final.parent.mkdir(parents=True)
        os.replace(staging, final)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return Submission(campaign_id, spec, final, overrides)


def load_frozen(campaign_dir: Path) -> CampaignSpec:
    """The spec of an accepted campaign, from its frozen inputs."""
    return campaigns.load_spec(input_dir(campaign_dir) / SPEC_NAME)


def remove_staging_leftovers(data: Path) -> None:
    """Staging directories of a server killed while validating (never a campaign: those are moved out)."""
    shutil.rmtree(data / "staging", ignore_errors=True)


def _parsed(text: str) -> dict:
    """The TOML document ``text``, refused (one problem) when unreadable, too costly to parse, or nested beyond
    :data:`MAX_NESTING`."""
    too_deep = SpecError([f"spec: tables and arrays nested more than {MAX_NESTING} levels deep (the built-in specs "
                          "nest 4)"])
    _check_shape(text, too_deep)
    try:
        parsed = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError([f"spec: not valid TOML ({exc})"]) from None
    except ValueError as exc:  # Python's own limits, e.g. an integer of more than 4300 digits (no advice to heed)
        raise SpecError([f"spec: not readable ({str(exc).partition(';')[0]})"]) from None
    except RecursionError:  # tomllib recurses into nesting: should the scan ever miss one, one line still, no 500
        raise too_deep from None
    # a table header, a dotted key and a value may each nest within the bound and all together beyond it: measure
    pending = [(parsed, 1)]
    while pending:
        value, depth = pending.pop()
        if depth > MAX_NESTING:
            raise too_deep
        children = value.values() if isinstance(value, dict) else value
        pending += [(child, depth + 1) for child in children if isinstance(child, dict | list)]
    return parsed


#: What the scan of a spec stops at: anything but the characters of a bare key and blanks.
_SPECIAL = re.compile(r"[^A-Za-z0-9_ \t-]")
#: The rest of a string after its opening quotes. A one-line string ends at its line's end at the latest, so that
#: whatever a malformed one holds, the scan is back in step with the parser on the next line.
_STRING_REST = {
    '"""': re.compile(r'(?:[^"\\]|\\.|"(?!""))*(?:"""|$)', re.DOTALL),
    "'''": re.compile(r"(?:[^']|'(?!''))*(?:'''|$)"),
    '"': re.compile(r'(?:[^"\\\n]|\\.)*(?:"|\n|$)'),
    "'": re.compile(r"[^'\n]*(?:'|\n|$)"),
}


def _check_shape(text: str, too_deep: SpecError) -> None:
    """Refuse, in one pass over ``text`` before it is parsed, what would make tomllib work too hard: arrays and
    inline tables nested beyond :data:`MAX_NESTING` (it recurses into each), or a dotted key or table name of more
    parts (it builds a key part by part, in quadratic time: 10000 parts take seconds, a 256 kB spec of them a
    quarter of an hour). Strings and comments are skipped as the parser skips them.
    """
    depth = parts = 0
    k = 0
    while found := _SPECIAL.search(text, k):
        char, k = found.group(), found.end()
        if char in "\"'":
            opener = char * 3 if text.startswith(char * 3, found.start()) else char
            k = _STRING_REST[opener].match(text, found.start() + len(opener)).end()
            continue  # a quoted part of a dotted key is a part of the key
        if char == "#":
            k = len(text) if (end := text.find("\n", k)) < 0 else end
        elif char in "[{":
            depth += 1
            if depth > MAX_NESTING:
                raise too_deep
        elif char in "]}":
            depth = max(depth - 1, 0)
        elif char == ".":
            parts += 1
            if parts >= MAX_NESTING:
                line = text.count("\n", 0, k) + 1
                raise SpecError([f"spec: line {line}: a dotted key or table name of more than {MAX_NESTING} parts"])
            continue
        parts = 0


def _write(path: Path, text: str) -> None:
    with open(path, "w", encoding="utf-8") as handle:
        handle.write(text)
        handle.flush()
        os.fsync(handle.fileno())


def _structural_problems(parsed: dict) -> list[str]:
    """The spec's other problems, found without reading any file (when its path problems stop the full check).

    A spec that extends another is incomplete on its own: its structure is judged once merged, so not here.
    """
    if "extends" in parsed:
        return []
    try:
        validate_spec(parsed, None)
    except SpecError as exc:
        return exc.problems
    return []


def _reach_problems(parsed: dict) -> list[str]:
    """Fields that would make the server read files of the submitter's choosing: paths instead of names.

    A bare word that is not a built-in name goes on to the library, which reports it as unknown with the
    rest of the spec's problems (the server runs in its data directory, so a bare word names nothing else).
    """
    problems = []
    extends = parsed.get("extends")
    if extends is not None and extends not in builtin_specs():
        problems.append(f"extends: the service extends built-in specs only ({', '.join(builtin_specs())}), "
                        f"got {extends!r}")
    base = parsed.get("base") if isinstance(parsed.get("base"), dict) else {}
    named = [("base.scene", base.get("scene"), twin.list_scenes()),
             ("base.parameters", base.get("parameters"), available_parameter_sets())]
    datasets = parsed.get("datasets") if isinstance(parsed.get("datasets"), list) else []
    named += [(f"datasets[{k}].scene", d.get("scene"), twin.list_scenes())
              for k, d in enumerate(datasets) if isinstance(d, dict)]
    for path, value, known in named:
        if isinstance(value, str) and not _BARE_NAME.match(value):
            problems.append(f"{path}: the service accepts built-in names only ({', '.join(known)}), not paths; "
                            f"got {value!r}")
    return problems
