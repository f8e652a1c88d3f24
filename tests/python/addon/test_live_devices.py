"""The session panel's Device menu from the real servo's `--list-devices --json` (hidapi finds
no device here: a valid listing), the binding each item makes, the panel's settings refused
above the chosen device's limits, and a servo path that fails said plainly in the panel."""

import json
import stat
from pathlib import Path

import blender_scene
import bpy
import pytest


@pytest.fixture()
def scene(addon, tmp_path):
    from addon.live import device_list, live_link

    device_list.forget()
    scene = blender_scene.finger_scene(str(tmp_path))
    yield scene
    live_link.stop()
    device_list.forget()


def panel_texts() -> list[str]:
    from test_addon_panels import CheckingLayout, draw

    from addon.ui import live_panels

    layout = CheckingLayout()
    draw(live_panels.HAPTICUT_PT_live, layout)
    return layout.texts


def script(tmp_path: Path, name: str, body: str) -> str:
    path = tmp_path / name
    path.write_text("#!/bin/sh\n" + body + "\n")
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return str(path)


def test_the_real_listing_fills_the_menu_and_each_item_makes_its_binding(scene):
    from addon.live import device_list, live_link, live_properties
    from addon.toolkit import toolkit_link

    settings = scene.hapticut_live
    assert bpy.ops.hapticut.refresh_devices() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert settings.device_error == ""
    listing = device_list.cached()
    # The servo's own answer, checked against what it was run on: every shipped profile file.
    servo = toolkit_link.link(blender_scene.toolkit_executable()).servo
    files = {p.stem for p in Path(listing["profile_directory"]).glob("*.json")}
    shipped = [p["name"] for p in listing["profiles"]]
    assert files and sorted(shipped) == sorted(files)
    assert {k["kind"] for k in listing["kinds"]} == {"sim", "viewport", "bridge"}
    print(f"\n{servo} --list-devices --json: {len(listing['devices'])} HID devices")

    identifiers = [item[0] for item in live_properties.device_items(settings)]
    assert identifiers[:3] == ["VIEWPORT", "SIM", "BRIDGE"]
    assert [i for i in identifiers if i.startswith("HID:")] == [
        f"HID:{name}"
        for name in dict.fromkeys(
            [d["profile"] for d in listing["devices"] if d["profile"]] + shipped
        )
    ]
    assert identifiers[-2:] == ["BLADES", "CUSTOM"]
    # Each connected device is offered with the profile it matched (none here, but the code
    # that labels them runs on whatever hidapi found).
    choices = {c.identifier: c for c in device_list.choices(listing)}
    for device in listing["devices"]:
        if device["profile"]:
            assert device["path"] in choices[f"HID:{device['profile']}"].description

    knife = bpy.data.objects["Knife"]
    knife.hapticut.device = "replay:stroke.rec"
    settings.bridge_port, settings.custom_device = 47999, "sim:press"
    expected = {
        "VIEWPORT": "viewport",
        "SIM": "sim",
        "BRIDGE": "bridge:port=47999",
        "BLADES": "replay:stroke.rec",
        "CUSTOM": "sim:press",
        **{f"HID:{name}": f"hid:{name}" for name in shipped},
    }
    for identifier, binding in expected.items():
        settings.device_mode = identifier
        assert settings.device_mode == identifier and settings.device_choice == identifier
        assert live_link.devices(scene) == [f"Knife={binding}"]
    with pytest.raises(TypeError):
        settings.device_mode = "HID:no-such-profile"
    # The chosen item's limits are the listing's.
    settings.device_mode = "BRIDGE"
    bridge = next(k for k in listing["kinds"] if k["kind"] == "bridge")
    assert live_properties.choice(settings).limits == bridge["limits"]
    assert f"device limits: {device_list.limits_text(bridge['limits'])}" in panel_texts()
    settings.device_mode = f"HID:{shipped[0]}"
    profile = listing["profiles"][0]
    assert live_properties.choice(settings).limits == profile["limits"]


def test_a_force_dimension_arm_the_servo_sees_is_offered_and_bound(scene, monkeypatch):
    """An arm Force Dimension's library sees (the DHD stand-in in its place) is an item of the
    menu with its model and limits, and makes its forcedimension binding; a binding's own
    limit options and scale change the limits the panel checks against."""
    from addon.live import device_list, live_link, live_properties
    from tests.python.standin_support import DHD_STANDIN, built_standin

    monkeypatch.setenv("HAPTICUT_DHD_LIB", str(built_standin(DHD_STANDIN)))
    monkeypatch.setenv("HAPTICUT_DHD_STANDIN", "devices=1,type=60")  # A Novint Falcon.
    settings = scene.hapticut_live
    assert bpy.ops.hapticut.refresh_devices() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert settings.device_error == ""
    listing = device_list.cached()
    arm = listing["forcedimension"]["devices"][0]
    identifiers = [item[0] for item in live_properties.device_items(settings)]
    assert identifiers[-3:] == ["FORCEDIMENSION:0", "BLADES", "CUSTOM"]
    settings.device_mode = "FORCEDIMENSION:0"
    chosen = live_properties.choice(settings)
    assert chosen.label == "Novint Falcon (forcedimension:0)"
    assert chosen.limits == arm["limits"] and arm["limits"]["has_force_output"] is True
    assert live_link.devices(scene) == ["Knife=forcedimension:0"]
    assert device_list.limits_for(listing, "forcedimension:0,max_force=1")["max_force_N"] == 1
    assert device_list.limits_for(listing, "forcedimension:3") == {}  # Not listed.
    scaled = device_list.limits_for(listing, "forcedimension:scale=2")
    assert scaled["max_stiffness_N_per_mm"] == arm["limits"]["max_stiffness_N_per_mm"] / 2
    assert device_list.STIFFNESS_AT_RATE not in scaled


def test_a_touch_openhaptics_opens_is_offered_and_bound(scene, monkeypatch):
    """The Touch OpenHaptics's library opens (the HD stand-in in its place) is an item of the
    menu with its limits, and makes the openhaptics binding; a binding's own limit options
    and scale change the limits the panel checks against."""
    from addon.live import device_list, live_link, live_properties
    from tests.python.standin_support import HD_STANDIN, built_standin

    monkeypatch.setenv("HAPTICUT_OPENHAPTICS_LIB", str(built_standin(HD_STANDIN)))
    monkeypatch.setenv("HAPTICUT_HD_STANDIN", "continuous=0.88,stiffness=1.2")
    settings = scene.hapticut_live
    assert bpy.ops.hapticut.refresh_devices() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert settings.device_error == ""
    listing = device_list.cached()
    touch = listing["openhaptics"]["devices"][0]
    identifiers = [item[0] for item in live_properties.device_items(settings)]
    assert identifiers[-3:] == ["OPENHAPTICS", "BLADES", "CUSTOM"]
    settings.device_mode = "OPENHAPTICS"
    chosen = live_properties.choice(settings)
    assert chosen.label == "3D Systems Touch (openhaptics)"
    assert chosen.limits == touch["limits"] and touch["limits"]["max_force_N"] == 0.88
    assert live_link.devices(scene) == ["Knife=openhaptics"]
    assert device_list.limits_for(listing, "openhaptics:max_force=0.5")["max_force_N"] == 0.5
    assert device_list.limits_for(listing, "openhaptics:Other") == {}  # Not listed.
    scaled = device_list.limits_for(listing, "openhaptics:scale=2")
    assert scaled["max_stiffness_N_per_mm"] == 0.6
    assert device_list.STIFFNESS_AT_RATE not in scaled


def test_a_choice_saved_before_its_listing_stays_offered(scene):
    from addon.live import live_link, live_properties

    settings = scene.hapticut_live
    settings.device_choice = "HID:spacemouse-pro"  # As a reopened .blend holds it.
    items = live_properties.device_items(settings)
    assert items[-1][0] == "HID:spacemouse-pro" and "Refresh devices" in items[-1][1]
    assert settings.device_mode == "HID:spacemouse-pro"
    assert live_link.devices(scene) == ["Knife=hid:spacemouse-pro"]
    assert "device limits: Refresh devices to read them" in panel_texts()


def test_settings_above_the_devices_limits_are_refused(scene):
    from addon.live import device_list, live_link

    settings = scene.hapticut_live
    assert bpy.ops.hapticut.refresh_devices() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    listing = device_list.cached()
    bridge = next(k for k in listing["kinds"] if k["kind"] == "bridge")["limits"]
    sim = next(k for k in listing["kinds"] if k["kind"] == "sim")["limits"]
    assert bridge["max_stiffness_N_per_mm"] > 0 and sim["max_force_N"] > 0
    # The limit and the rate against one point's spring: the paper's independent points (a
    # rigid blade's sum of springs: test_a_rigid_blades_stiffness_is_its_points_springs).
    knife = bpy.data.objects["Knife"]
    knife.hapticut.blade_coupling = "INDEPENDENT"

    settings.device_mode = "BRIDGE"
    settings.stiffness_N_per_mm = 2 * bridge["max_stiffness_N_per_mm"]
    with pytest.raises(RuntimeError, match="stiffness .* is above the device's"):
        bpy.ops.hapticut.go_live()
        bpy.ops.hapticut.wait()
    assert live_link.current() is None  # Refused before any servo started.
    assert f"{bridge['max_stiffness_N_per_mm']:g} N/mm" in settings.error
    assert any("Go Live refuses it" in text for text in panel_texts())
    settings.stiffness_N_per_mm = 0.5 * bridge["max_stiffness_N_per_mm"]
    live_link.check_limits(
        bpy.context, live_link.devices(scene), live_link.requested_settings(settings)
    )
    assert not any("Go Live refuses it" in text for text in panel_texts())
    # The limit at another rate is the servo's (--list-devices --json --rate): Go Live reads
    # the listing again at the panel's rate and compares with its limit there. 0.75 x the
    # 1 kHz limit passes at 1 kHz; at 500 Hz the servo's limit is half of it.
    assert device_list.listed_rate() == 1000.0
    assert bridge["max_stiffness_N_per_mm_at_rate"] == bridge["max_stiffness_N_per_mm"]
    settings.rate_Hz = 500.0
    settings.stiffness_N_per_mm = 0.75 * bridge["max_stiffness_N_per_mm"]
    # Drawn before it is read at 500 Hz: the panel says its limit is for another rate.
    assert any("read at 1000 Hz: Refresh devices for 500 Hz" in t for t in panel_texts())
    with pytest.raises(RuntimeError, match="stiffness .* is above the device's") as refused:
        bpy.ops.hapticut.go_live()
        bpy.ops.hapticut.wait()
    assert live_link.current() is None
    assert device_list.listed_rate() == 500.0
    slow = next(k for k in device_list.cached()["kinds"] if k["kind"] == "bridge")["limits"]
    at_500 = slow["max_stiffness_N_per_mm_at_rate"]
    assert at_500 == pytest.approx(0.5 * bridge["max_stiffness_N_per_mm"])
    stated = bridge["max_stiffness_N_per_mm"]
    stated_rate = slow["max_stiffness_stated_rate_Hz"]
    assert stated_rate == 1000.0
    assert (
        f"above the device's {at_500:g} N/mm at 500 Hz ({stated:g} N/mm as stated, for 1000 Hz)"
        in str(refused.value)
    )
    assert any("Go Live refuses it" in text for text in panel_texts())
    assert not any("Refresh devices for" in text for text in panel_texts())
    settings.rate_Hz = 1000.0
    live_link.check_limits(
        bpy.context, live_link.devices(scene), live_link.requested_settings(settings)
    )
    assert device_list.listed_rate() == 1000.0
    # A bridge bound with a lower force limit of its own: that one counts.
    settings.device_mode = "CUSTOM"
    settings.custom_device = f"bridge:port=0,max_force={bridge['max_force_N'] / 2}"
    settings.max_force_N = 0.75 * bridge["max_force_N"]
    with pytest.raises(RuntimeError, match="max force .* is above the device's"):
        bpy.ops.hapticut.go_live()
        bpy.ops.hapticut.wait()
    settings.max_force_N = 0.0
    # A stiffness limit of its own: known at a rate only to the servo, whose "set" refuses a
    # stiffness above it (test_servo_stiffness_limit.py); the add-on claims no limit there.
    lower = 0.25 * bridge["max_stiffness_N_per_mm"]
    settings.custom_device = f"bridge:port=0,max_stiffness={lower}"
    own = device_list.limits_for(device_list.cached(), settings.custom_device)
    assert own["max_stiffness_N_per_mm"] == lower
    assert device_list.STIFFNESS_AT_RATE not in own
    live_link.check_limits(
        bpy.context, live_link.devices(scene), live_link.requested_settings(settings)
    )
    settings.stiffness_N_per_mm = 0.0

    settings.device_mode = "SIM"
    settings.max_force_N = sim["max_force_N"] + 1
    with pytest.raises(RuntimeError, match="max force .* is above the device's"):
        bpy.ops.hapticut.go_live()
        bpy.ops.hapticut.wait()
    settings.max_force_N = sim["max_force_N"]
    live_link.check_limits(
        bpy.context, live_link.devices(scene), live_link.requested_settings(settings)
    )
    # An input-only device renders no force: its force limit does not apply.
    settings.device_mode = f"HID:{listing['profiles'][0]['name']}"
    assert not listing["profiles"][0]["limits"]["has_force_output"]
    live_link.check_limits(
        bpy.context, live_link.devices(scene), live_link.requested_settings(settings)
    )
    settings.max_force_N = 0.0


def test_a_rigid_blades_stiffness_is_its_points_springs(scene):
    """A rigid blade renders n k in contact (its n point springs act together): the device's
    stiffness limit bounds that sum, so a point stiffness within the limit is refused for a
    rigid 20-point blade, and one under limit / 20 is taken."""
    from addon.live import device_list, live_link

    settings = scene.hapticut_live
    assert bpy.ops.hapticut.refresh_devices() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    bridge = next(k for k in device_list.cached()["kinds"] if k["kind"] == "bridge")["limits"]
    limit = bridge["max_stiffness_N_per_mm_at_rate"]
    knife = bpy.data.objects["Knife"]
    assert (knife.hapticut.blade_coupling, knife.hapticut.blade_points) == ("RIGID", 20)
    assert live_link.blade_springs(scene, "Knife") == live_link.blade_springs(scene) == 20
    settings.device_mode = "BRIDGE"
    settings.stiffness_N_per_mm = 0.5 * limit
    with pytest.raises(live_link.live_session.LiveServoError) as refused:
        live_link.check_limits(
            bpy.context, live_link.devices(scene), live_link.requested_settings(settings)
        )
    assert f"stiffness {10 * limit:g} N/mm ({0.5 * limit:g} N/mm x 20 points of a rigid blade)" in (
        str(refused.value)
    )
    assert any("Go Live refuses it" in text for text in panel_texts())
    settings.stiffness_N_per_mm = 0.9 * limit / 20
    live_link.check_limits(
        bpy.context, live_link.devices(scene), live_link.requested_settings(settings)
    )
    assert not any("Go Live refuses it" in text for text in panel_texts())
    knife.hapticut.blade_coupling = "INDEPENDENT"
    assert live_link.blade_springs(scene) == 1
    settings.stiffness_N_per_mm = 0.5 * limit
    live_link.check_limits(
        bpy.context, live_link.devices(scene), live_link.requested_settings(settings)
    )
    settings.stiffness_N_per_mm = 0.0


def test_a_servo_that_fails_to_list_is_said_so_in_the_panel(scene, tmp_path, monkeypatch):
    from addon.live import device_list, live_properties
    from addon.toolkit import toolkit_link

    settings = scene.hapticut_live
    assert bpy.ops.hapticut.refresh_devices() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    listed = device_list.cached()
    link = toolkit_link.link(blender_scene.toolkit_executable())
    monkeypatch.setattr(device_list, "LIST_TIMEOUT_S", 0.5)
    broken = {
        "/nonexistent/hapticut-servo": "cannot run /nonexistent/hapticut-servo",
        script(tmp_path, "fails", "echo 'hapticut-servo: --list-devices: no profiles' >&2; exit 4"):
            "failed (code 4): hapticut-servo: --list-devices: no profiles",
        script(tmp_path, "prose", "echo 'no HID devices found'"): "printed no JSON",
        script(tmp_path, "other", "echo '{\"version\": 7}'"): "not a version 1 device listing",
        # A servo older than the add-on: its listing has no limits at a rate.
        script(tmp_path, "old", "echo '{\"version\": 1, \"devices\": [], \"profiles\": [], "
               "\"kinds\": []}'"): "gave no limits at 1000 Hz",
        script(tmp_path, "hangs", "exec sleep 30"): "did not answer within 0.5 s",
    }  # fmt: skip
    for servo, message in broken.items():
        monkeypatch.setattr(link, "servo", servo)
        with pytest.raises(RuntimeError, match="devices not listed"):
            bpy.ops.hapticut.refresh_devices()
            bpy.ops.hapticut.wait()
        assert message in settings.device_error, settings.device_error
        assert settings.device_error in panel_texts()
        # The listing read before stays, and so does the menu made of it.
        assert device_list.cached() is listed
        assert any(i[0].startswith("HID:") for i in live_properties.device_items(settings))
    # Limits needed but not listable: Go Live says why instead of running unchecked.
    device_list.forget()
    settings.stiffness_N_per_mm = 0.5
    with pytest.raises(RuntimeError, match="devices not listed"):
        bpy.ops.hapticut.go_live()
        bpy.ops.hapticut.wait()
    settings.stiffness_N_per_mm = 0.0
    # A toolkit that hangs when asked where its servo is: the same bound.
    monkeypatch.setattr(toolkit_link, "_link", None)
    prefs = bpy.context.preferences.addons[blender_scene.ADDON_MODULE].preferences
    saved, prefs.toolkit_path = prefs.toolkit_path, script(tmp_path, "toolkit", "exec sleep 30")
    try:
        with pytest.raises(RuntimeError, match="devices not listed: hapticut paths"):
            bpy.ops.hapticut.refresh_devices()
            bpy.ops.hapticut.wait()
        assert "timed out after 0.5 seconds" in settings.device_error, settings.device_error
    finally:
        prefs.toolkit_path = saved
    monkeypatch.undo()
    assert bpy.ops.hapticut.refresh_devices() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert settings.device_error == ""
    print(json.dumps({"devices": len(device_list.cached()["devices"])}))
