"""The device profiles as shipped: valid against their schema, in the wheel, and
each one's USB ids in the udev rule file (docs/devices.md)."""

import json
import re
from pathlib import Path

import hapticut
import jsonschema
import pytest

SOURCE = Path(__file__).resolve().parents[2] / "core" / "hapticut" / "devices"
INSTALLED = Path(hapticut.__file__).resolve().parent / "devices"
TEST_PROFILE = (
    Path(__file__).resolve().parents[2]
    / "server"
    / "devices"
    / "tests"
    / "data"
    / "example-force-device.json"
)


def schema() -> dict:
    return json.loads((SOURCE / "profile.schema.json").read_text())


def shipped() -> list[Path]:
    return sorted((SOURCE / "profiles").glob("*.json"))


def validator() -> jsonschema.Draft202012Validator:
    jsonschema.Draft202012Validator.check_schema(schema())
    return jsonschema.Draft202012Validator(schema())


@pytest.mark.parametrize("path", [*shipped(), TEST_PROFILE], ids=lambda p: p.stem)
def test_profile_is_valid_against_the_schema_and_named_after_its_file(path):
    profile = json.loads(path.read_text())
    validator().validate(profile)
    assert profile["name"] == path.stem


def test_schema_refuses_what_the_cpp_reader_refuses():
    profile = json.loads(shipped()[0].read_text())
    bad_width = json.loads(json.dumps(profile))
    bad_width["input"]["reports"][0]["axes"][0]["width"] = 3
    unknown = json.loads(json.dumps(profile))
    unknown["colour"] = "blue"
    bad_output = json.loads(json.dumps(profile))
    bad_output["output"] = "some"
    for broken in (bad_width, unknown, bad_output):
        assert list(validator().iter_errors(broken)), broken


def test_every_shipped_profile_has_its_udev_rule():
    rules = (SOURCE / "70-hapticut.rules").read_text()
    pairs = set(re.findall(r'idVendor}=="([0-9a-f]{4})", ATTRS{idProduct}=="([0-9a-f]{4})"', rules))
    for path in shipped():
        match = json.loads(path.read_text())["match"]
        vendor = match["vendor_id"].lower().removeprefix("0x").zfill(4)
        for product in match["product_ids"]:
            assert (vendor, product.lower().removeprefix("0x").zfill(4)) in pairs, path.name
    assert all('TAG+="uaccess"' in line for line in rules.splitlines() if "KERNEL" in line)


def test_the_package_ships_profiles_schema_and_rules():
    assert sorted(p.name for p in (INSTALLED / "profiles").glob("*.json")) == [
        p.name for p in shipped()
    ]
    assert (INSTALLED / "profile.schema.json").is_file()
    assert (INSTALLED / "70-hapticut.rules").is_file()
