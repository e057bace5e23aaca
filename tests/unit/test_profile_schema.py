"""The JSON Schema shipped beside the profiles (an editor's YAML language server validates and completes a profile
with it): it is the one the pydantic models generate, and an independent validator (``jsonschema``) accepts every
shipped profile under it and refuses what ``load_profile`` refuses for the same reason."""

from __future__ import annotations

import json

import pytest
import yaml

from pickplace_cli import ProfileError, load_profile, parse_profile, profile_schema, shipped_profiles
from pickplace_cli.model.profile import SCHEMA_FILE
from pickplace_cli.model.resources import data_dir

SHIPPED = data_dir("profiles") / SCHEMA_FILE
REGENERATE = ("regenerate it: python -c \"import json, pickplace_cli as p; open('profiles/profile.schema.json', 'w')"
              ".write(json.dumps(p.profile_schema(), indent=2, ensure_ascii=False) + '\\n')\"")


def test_shipped_schema_is_the_generated_one():
    assert json.loads(SHIPPED.read_text(encoding="utf-8")) == profile_schema(), f"{SHIPPED} is stale: {REGENERATE}"


@pytest.fixture(scope="module")
def validator():
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads(SHIPPED.read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


@pytest.mark.parametrize("name", sorted(shipped_profiles()))
def test_every_shipped_profile_names_the_schema_and_is_valid_under_it(name, validator):
    path = shipped_profiles()[name]
    text = path.read_text(encoding="utf-8")
    assert text.splitlines()[0] == f"# yaml-language-server: $schema={SCHEMA_FILE}"
    assert (path.parent / SCHEMA_FILE).is_file()
    assert list(validator.iter_errors(yaml.safe_load(text))) == []
    load_profile(name)


@pytest.mark.parametrize("old,new", [
    ("gear_ratio: 25.0", "gear_raito: 25.0"),            # a misspelt key
    ("velocity: 5.0", "velocity: -5.0"),                 # capacity must be > 0
    ("kind: delta", "kind: hexapod"),                    # no such robot
    ("eta: 0.5", "eta: 1.5"),                            # 0 < η < 1
])
def test_schema_refuses_what_the_loader_refuses(old, new, validator):
    text = shipped_profiles()["delta-su2018"].read_text(encoding="utf-8")
    assert old in text
    bad = text.replace(old, new, 1)
    assert list(validator.iter_errors(yaml.safe_load(bad))), f"the schema accepts {new!r}"
    with pytest.raises(ProfileError):
        parse_profile(bad, "p.yaml")


def test_profile_init_points_the_copy_at_the_shipped_schema(tmp_path):
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    out = tmp_path / "mine.yaml"
    r = CliRunner().invoke(app, ["profile", "init", "delta-su2018", str(out)])
    assert r.exit_code == 0
    first, *rest = out.read_text(encoding="utf-8").splitlines()
    prefix = "# yaml-language-server: $schema="
    assert first.startswith(prefix) and (target := first[len(prefix):]) != SCHEMA_FILE
    assert json.loads(open(target, encoding="utf-8").read()) == profile_schema()
    assert rest == shipped_profiles()["delta-su2018"].read_text(encoding="utf-8").splitlines()[1:]
