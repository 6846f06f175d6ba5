"""`paracosm-fuzz export` (issue 21, requirement 5): the OpenSCENARIO files it writes are
valid against ASAM's OpenSCENARIO 1.2 XSD, and the OpenDRIVE files against ASAM's OpenDRIVE
1.7 XSD, both as shipped in the `scenariogeneration` package (its `schemas/` folder)."""

import subprocess
from pathlib import Path

import pytest
import scenariogeneration
import xmlschema

SCHEMAS = Path(scenariogeneration.__file__).resolve().parent.parent / "schemas"


@pytest.fixture(scope="module")
def schemas():
    return {
        "xosc": xmlschema.XMLSchema(str(SCHEMAS / "OpenSCENARIO_1_2.xsd")),
        "xodr": xmlschema.XMLSchema(str(SCHEMAS / "opendrive_17_core.xsd")),
    }


@pytest.mark.parametrize(
    "scenario,budget,test_id",
    [
        # An OpenDRIVE map with a pedestrian that walks when the ego comes near.
        ("curve-pedestrian", "30", None),
        # Pieces: segments and T-intersections, an NPC car and a pedestrian.
        ("t-loop", "1", 0),
        # Pieces: a roundabout and four roads, three cars.
        ("roundabout", "2", 1),
        # An OpenDRIVE junction, two cars.
        ("opendrive-junction", "4", 1),
    ],
)
def test_exports_are_valid_against_the_asam_schemas(tmp_path, paracosm_fuzz, schemas, scenario, budget, test_id):
    out = tmp_path / "campaign"
    run = subprocess.run(
        [str(paracosm_fuzz), scenario, "--budget", budget, "--out", str(out)],
        capture_output=True,
        text=True,
    )
    assert run.returncode in (0, 1), run.stderr
    if test_id is None:
        # A failing test (a collision with the pedestrian).
        import json

        lines = [json.loads(l) for l in (out / "results.jsonl").read_text().splitlines()]
        test_id = next(r["id"] for r in lines if r["status"] == "fail")
    export = tmp_path / "export"
    done = subprocess.run(
        [str(paracosm_fuzz), "export", str(out / "results.jsonl"), "--id", str(test_id), "--out", str(export)],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    for kind in ("xosc", "xodr"):
        path = export / f"test_{test_id}.{kind}"
        errors = [str(e) for e in schemas[kind].iter_errors(str(path))]
        assert errors == [], f"{path}:\n" + "\n".join(errors[:5])
    xosc = (export / f"test_{test_id}.xosc").read_text()
    assert f'<LogicFile filepath="test_{test_id}.xodr"/>' in xosc


def test_the_schemas_catch_what_is_wrong(tmp_path, schemas):
    """The check can fail: an element OpenSCENARIO does not have, a road without its
    length."""
    bad = tmp_path / "bad.xosc"
    bad.write_text('<?xml version="1.0"?><OpenSCENARIO><FileHeader revMajor="1" revMinor="2" '
                   'date="1970-01-01T00:00:00" description="" author=""/><Bogus/></OpenSCENARIO>')
    assert list(schemas["xosc"].iter_errors(str(bad)))
    road = tmp_path / "bad.xodr"
    road.write_text('<OpenDRIVE><header revMajor="1" revMinor="6"/><road id="1" junction="-1"/></OpenDRIVE>')
    assert list(schemas["xodr"].iter_errors(str(road)))
