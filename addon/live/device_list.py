"""The devices the session panel offers, from ``hapticut-servo --list-devices --json`` (run as a
child process, at most ``LIST_TIMEOUT_S``), and the limits of the device a binding names.

The listing (docs/devices.md) holds the HID devices hidapi finds with the profile each matches, the
shipped profiles, the other kinds (sim, viewport, bridge), the Force Dimension arms its library sees
and the 3D Systems Touch OpenHaptics opens, each with its limits, the stiffness limit among them at
the loop rate the listing was asked for (``--rate``: the servo's own rule, so the add-on has none).
It is read on *Refresh devices* (and when a check needs limits at a rate the kept one was not read
at) and kept; the panel's items are made from the kept listing only, so drawing never runs a
process.
No bpy here.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

from ..background import steps
from ..toolkit import runner

LIST_TIMEOUT_S = 10.0
BRIDGE_DEFAULT_PORT = 47810


class DeviceListError(RuntimeError):
    """The listing could not be read; the message is for the panel."""


@dataclass(frozen=True)
class Choice:
    """One item of the panel's Device menu."""

    # VIEWPORT, SIM, BRIDGE, HID:<profile>, FORCEDIMENSION:<id>, OPENHAPTICS[:<name>], BLADES,
    # CUSTOM
    identifier: str
    label: str
    description: str
    limits: dict = field(default_factory=dict)  # The listing's limits; {} unknown.


# Offered with or without a listing: the modes that need no device found.
VIEWPORT = Choice(
    "VIEWPORT", "Viewport", "Move the blade objects in the viewport (grab, rotate, playback)"
)
SIM = Choice("SIM", "Sim", "The servo's built-in simulated stroke (press, then slide)")
BRIDGE = Choice("BRIDGE", "UDP bridge", "A force device behind a UDP bridge (its port below)")
BLADES = Choice(
    "BLADES", "Blade devices", "Each blade's own Device field (any --device text per blade)"
)
CUSTOM = Choice("CUSTOM", "Custom", "One --device text for every blade (e.g. sim:path.json)")
FIXED_KINDS = {"VIEWPORT": "viewport", "SIM": "sim", "BRIDGE": "bridge"}

_listing: dict | None = None
_generation = 0  # Bumped at every new listing (the panel's items are cached per generation).


def listing_steps(
    servo: str, timeout_s: float | None = None, rate_Hz: float = 1000.0
) -> steps.Steps[dict]:
    """``servo --list-devices --json --rate rate_Hz``, checked, as steps; DeviceListError
    naming what went wrong. The child is killed after timeout_s (LIST_TIMEOUT_S)."""
    timeout_s = LIST_TIMEOUT_S if timeout_s is None else timeout_s
    command = [servo, "--list-devices", "--json", "--rate", repr(float(rate_Hz))]
    try:
        done = yield from steps.child(
            command, timeout_s, "listing the devices", runner.child_environment()
        )
    except steps.ChildTimeoutError:
        raise DeviceListError(
            f"{servo} --list-devices did not answer within {timeout_s:.3g} s"
        ) from None
    except OSError as error:
        raise DeviceListError(f"cannot run {servo}: {error}") from None
    if done.returncode != 0:
        line = runner.last_error_line(done.stderr)
        raise DeviceListError(f"{servo} --list-devices failed (code {done.returncode}): {line}")
    try:
        listing = json.loads(done.stdout)
    except json.JSONDecodeError as error:
        raise DeviceListError(f"{servo} --list-devices --json printed no JSON ({error})") from None
    if not isinstance(listing, dict) or listing.get("version") != 1:
        raise DeviceListError(f"{servo} --list-devices --json: not a version 1 device listing")
    for key in ("devices", "profiles", "kinds"):
        if not isinstance(listing.get(key), list):
            raise DeviceListError(f"{servo} --list-devices --json: no {key!r} list")
    if listing.get("rate_Hz") != float(rate_Hz):
        raise DeviceListError(
            f"{servo} --list-devices --json gave no limits at {rate_Hz:g} Hz "
            "(a servo older than the add-on?)"
        )
    return listing


def refresh_steps(
    servo: str, timeout_s: float | None = None, rate_Hz: float = 1000.0
) -> steps.Steps[dict]:
    """Read the listing again at this loop rate and keep it (a failure keeps the previous
    one)."""
    global _listing, _generation
    _listing = yield from listing_steps(servo, timeout_s, rate_Hz)
    _generation += 1
    return _listing


def cached() -> dict | None:
    return _listing


def listed_rate() -> float | None:
    """The loop rate the kept listing's stiffness limits are for (None: no listing)."""
    return None if _listing is None else _listing["rate_Hz"]


def generation() -> int:
    return _generation


def forget() -> None:
    global _listing, _generation
    _listing = None
    _generation += 1


def limits_text(limits: dict) -> str:
    if not limits:
        return "limits not listed"
    if not limits.get("has_force_output"):
        return "input only, no force output"
    parts = [f"max force {limits.get('max_force_N', 0):g} N"]
    if limits.get("max_stiffness_N_per_mm", 0) > 0:
        parts.append(f"max stiffness {limits['max_stiffness_N_per_mm']:g} N/mm")
    return ", ".join(parts)


def forcedimension_devices(listing: dict) -> list[dict]:
    """The Force Dimension arms the listing's library opened (a servo older than the kind,
    or a library not found, lists none)."""
    found = listing.get("forcedimension") or {}
    return [d for d in found.get("devices", []) if not d.get("error")]


def openhaptics_devices(listing: dict) -> list[dict]:
    """The 3D Systems devices OpenHaptics's library opened (a servo older than the kind, or a
    library not found, lists none)."""
    found = listing.get("openhaptics") or {}
    return [d for d in found.get("devices", []) if not d.get("error")]


def _openhaptics_identifier(device: dict) -> str:
    return f"OPENHAPTICS:{device['name']}" if device.get("name") else "OPENHAPTICS"


def choices(listing: dict | None) -> list[Choice]:
    """The Device menu: viewport, sim, bridge, the HID devices found (with their profile),
    the shipped profiles not found (for a device plugged in later), the Force Dimension arms
    found, the 3D Systems devices OpenHaptics opens, blade devices, custom."""
    if listing is None:
        return [VIEWPORT, SIM, BRIDGE, BLADES, CUSTOM]
    kinds = {k["kind"]: k.get("limits", {}) for k in listing["kinds"]}
    fixed = [
        Choice(c.identifier, c.label, f"{c.description} ({limits_text(limits)})", limits)
        for c in (VIEWPORT, SIM, BRIDGE)
        for limits in [kinds.get(FIXED_KINDS[c.identifier], {})]
    ]
    profiles = {p["name"]: p for p in listing["profiles"]}
    found: dict[str, list[dict]] = {}
    for device in listing["devices"]:
        if device.get("profile"):
            found.setdefault(device["profile"], []).append(device)
    hid = []
    for name in [*found, *(n for n in profiles if n not in found)]:
        profile = profiles.get(name, {"name": name, "model": name})
        limits = profile.get("limits", {})
        devices = found.get(name, [])
        if devices:
            where = ", ".join(d.get("path", "?") for d in devices)
            label = f"{devices[0].get('product') or profile.get('model', name)} ({name})"
            text = f"Connected at {where}: hid:{name}"
        else:
            label = f"{profile.get('model', name)} ({name}, not connected)"
            text = f"Shipped profile, for a device plugged in later: hid:{name}"
        hid.append(Choice(f"HID:{name}", label, f"{text} ({limits_text(limits)})", limits))
    arms = [
        Choice(
            f"FORCEDIMENSION:{d['id']}",
            f"{d.get('model', 'Force Dimension device')} ({d['binding']})",
            f"Force Dimension arm through its SDK: {d['binding']} "
            f"({limits_text(d.get('limits', {}))})",
            d.get("limits", {}),
        )
        for d in forcedimension_devices(listing)
    ]
    touches = [
        Choice(
            _openhaptics_identifier(d),
            f"3D Systems Touch ({d['binding']})",
            f"3D Systems Touch or Phantom through OpenHaptics: {d['binding']} "
            f"({limits_text(d.get('limits', {}))})",
            d.get("limits", {}),
        )
        for d in openhaptics_devices(listing)
    ]
    return [*fixed, *hid, *arms, *touches, BLADES, CUSTOM]


def binding(identifier: str, bridge_port: int = BRIDGE_DEFAULT_PORT, custom: str = "") -> str:
    """The ``--device`` text of a menu item ("" for BLADES: each blade's own)."""
    if identifier == "VIEWPORT":
        return "viewport"
    if identifier == "SIM":
        return "sim"
    if identifier == "BRIDGE":
        return f"bridge:port={int(bridge_port)}"
    if identifier.startswith("HID:"):
        return f"hid:{identifier[4:]}"
    if identifier.startswith("FORCEDIMENSION:"):
        return f"forcedimension:{identifier[len('FORCEDIMENSION:') :]}"
    if identifier == "OPENHAPTICS":
        return "openhaptics"
    if identifier.startswith("OPENHAPTICS:"):
        return f"openhaptics:{identifier[len('OPENHAPTICS:') :]}"
    if identifier == "CUSTOM":
        return custom
    return ""


def _options(args: str) -> tuple[str, dict[str, str]]:
    bare, options = "", {}
    for i, part in enumerate(p for p in args.split(",") if p):
        key, sep, value = part.partition("=")
        if not sep and i == 0:
            bare = part
        elif sep:
            options[key.strip()] = value.strip()
    return bare, options


def _number(options: dict, key: str, default: float) -> float:
    try:
        return float(options[key]) if key in options else default
    except ValueError:
        return default  # The servo refuses the binding and names the option.


# The servo's stiffness limit at the listing's rate_Hz, in each entry's limits (docs/devices.md).
STIFFNESS_AT_RATE = "max_stiffness_N_per_mm_at_rate"

# The limit options of a binding text per kind: (option, limit).
LIMIT_OPTIONS = {
    "sim": (
        ("max_force_N", "max_force_N"),
        ("max_torque_N_mm", "max_torque_N_mm"),
        ("max_stiffness_N_per_mm", "max_stiffness_N_per_mm"),
    ),
    "bridge": (
        ("max_force", "max_force_N"),
        ("max_torque", "max_torque_N_mm"),
        ("max_stiffness", "max_stiffness_N_per_mm"),
    ),
    "forcedimension": (
        ("max_force", "max_force_N"),
        ("max_stiffness", "max_stiffness_N_per_mm"),
    ),
    "openhaptics": (
        ("max_force", "max_force_N"),
        ("max_stiffness", "max_stiffness_N_per_mm"),
    ),
}
# The kinds whose scale= divides the stiffness limit (a positional arm's, docs/devices.md).
SCALED_KINDS = ("forcedimension", "openhaptics")


def limits_for(listing: dict, device_text: str) -> dict:
    """The limits of the device a ``--device`` text binds, with its limit options applied
    (sim's max_force_N, max_torque_N_mm, max_stiffness_N_per_mm, the bridge's max_force, max_torque,
    max_stiffness, a Force Dimension arm's or a Touch's max_force, max_stiffness); {} when the
    listing does not know them (a profile file, replay, an unknown kind, an arm not listed). An
    arm's scale= divides its stiffness limit (the servo's rule, docs/devices.md), known here only as
    stated. A stiffness limit given in the text has no limit at the listing's rate here (only the
    servo knows it): the servo's ``set`` refuses a stiffness above it (docs/protocol.md)."""
    kind, _, args = device_text.strip().partition(":")
    bare, options = _options(args)
    if kind == "hid":
        name = options.get("profile", bare)
        profile = next((p for p in listing["profiles"] if p["name"] == name), None)
        if profile is None and not name:  # The first connected device a profile matches.
            first = next((d for d in listing["devices"] if d.get("profile")), None)
            name = first["profile"] if first else ""
            profile = next((p for p in listing["profiles"] if p["name"] == name), None)
        return dict(profile.get("limits", {})) if profile else {}
    if kind == "forcedimension":
        index = options.get("id", bare) or "0"
        arm = next((d for d in forcedimension_devices(listing) if str(d["id"]) == index), None)
        limits = dict(arm.get("limits", {})) if arm else {}
    elif kind == "openhaptics":
        name = options.get("device", bare)
        touch = next((d for d in openhaptics_devices(listing) if d.get("name", "") == name), None)
        limits = dict(touch.get("limits", {})) if touch else {}
    else:
        limits = dict(
            next((k.get("limits", {}) for k in listing["kinds"] if k["kind"] == kind), {})
        )
    keys = LIMIT_OPTIONS.get(kind, ()) if limits else ()
    for key, name in keys:
        if key in options:
            limits[name] = _number(options, key, limits.get(name, 0.0))
            if name == "max_stiffness_N_per_mm":
                limits.pop(STIFFNESS_AT_RATE, None)
    if kind in SCALED_KINDS and limits and "scale" in options:
        scale = _number(options, "scale", 1.0)
        if scale > 0:
            limits["max_stiffness_N_per_mm"] = limits.get("max_stiffness_N_per_mm", 0.0) / scale
            limits.pop(STIFFNESS_AT_RATE, None)
    return limits


# The panel's settings checked against a device's limits: (setting, limit, name, unit).
CHECKED = (
    ("max_force_N", "max_force_N", "max force", "N"),
    ("max_torque_N_mm", "max_torque_N_mm", "max torque", "N mm"),
    ("stiffness_N_per_mm", STIFFNESS_AT_RATE, "stiffness", "N/mm"),
)


def blade_springs(points: int, coupling: str) -> int:
    """The point springs a blade renders together in contact: all its points for a rigid blade
    (one pose: they act in parallel, n k whatever length of edge touches), one for independent
    points. The toolkit's rule (hapticut/stiffness.py) and the servo's; the add-on does not
    import the toolkit, hence stated here."""
    return max(1, int(points)) if coupling.upper() == "RIGID" else 1


def settings_problems(settings: dict, limits: dict, rate_Hz: float, springs: int = 1) -> list[str]:
    """What of the settings (as sent to the servo's ``set``) lies above the device's limits,
    from a listing read at the loop rate rate_Hz. Only known limits count: a force limit
    where the device renders force, the stiffness limit the servo gives at that rate
    (STIFFNESS_AT_RATE; 0 or absent: none known here). The stiffness is the point stiffness
    k; the limit bounds what the blade renders, ``springs`` x k (blade_springs)."""
    problems = []
    for setting, limit, name, unit in CHECKED:
        value, bound = settings.get(setting, 0.0), limits.get(limit, 0.0)
        asked = ""
        if setting == "stiffness_N_per_mm" and springs > 1:
            asked = f" ({value:g} {unit} x {springs} points of a rigid blade)"
            value *= springs
        if setting != "stiffness_N_per_mm" and not limits.get("has_force_output"):
            continue
        if value > 0 and bound > 0 and value > bound:
            if setting == "stiffness_N_per_mm":
                stated = limits.get("max_stiffness_N_per_mm", bound)
                stated_rate = limits.get("max_stiffness_stated_rate_Hz", 0.0)
                at_rate = f" at {rate_Hz:g} Hz"
                if stated != bound:
                    for_rate = f", for {stated_rate:g} Hz" if stated_rate > 0 else ""
                    at_rate += f" ({stated:g} {unit} as stated{for_rate})"
            else:
                at_rate = ""
            problems.append(
                f"{name} {value:g} {unit}{asked} is above the device's {bound:g} {unit}{at_rate}"
            )
    return problems
