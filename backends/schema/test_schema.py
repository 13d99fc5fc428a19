"""The published JSON Schema (schema/poser-scene.schema.json) checked by a real validator, as an
editor (taplo, VS Code) checks a scene with it: every shipped and test-input scene is valid,
`key = { unset = true }` is valid wherever a key is, and what poser refuses is refused."""

import json
import pathlib
import tomllib

import jsonschema
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCHEMA = json.loads((ROOT / "schema" / "poser-scene.schema.json").read_text())
VALIDATOR = jsonschema.validators.validator_for(SCHEMA)(SCHEMA)
SCENES = sorted(
    [*ROOT.glob("scenarios/**/*.toml"), *ROOT.glob("tests/in/*.toml")],
    key=lambda p: str(p),
)


def errors(doc):
    return [e.message for e in VALIDATOR.iter_errors(doc)]


def test_the_schema_is_a_valid_draft_2020_12_schema():
    assert SCHEMA["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    jsonschema.Draft202012Validator.check_schema(SCHEMA)


@pytest.mark.parametrize("scene", SCENES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_scene_validates(scene):
    assert len(SCENES) >= 40
    assert errors(tomllib.loads(scene.read_text())) == []


@pytest.mark.parametrize(
    "text",
    [
        # A dome variant of a flat-port base (docs/scenes.md).
        'include = ["base.toml"]\n[camera.port]\ntype = "dome"\npupil_distance = { unset = true }\n',
        # A whole table, a top-level table and a key of an array of tables.
        "[camera]\nport = { unset = true }\n",
        "water = { unset = true }\n",
        '[[lights]]\nname = "strobe"\ntype = "spot"\nbeam_angle = { unset = true }\n',
    ],
)
def test_unset_is_valid_wherever_a_key_is(text):
    assert errors(tomllib.loads(text)) == []


@pytest.mark.parametrize(
    "text",
    [
        "water = { unset = false }\n",
        "water = { unset = true, type = \"jerlov\" }\n",
        "[camera]\nbogus = 1\n",
        "[camera.port]\npupil_distanc = { unset = true }\n",
    ],
)
def test_what_poser_refuses_is_refused(text):
    assert errors(tomllib.loads(text)) != []
