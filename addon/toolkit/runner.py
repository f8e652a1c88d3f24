"""Reaching the ``hapticut`` toolkit: where it is, how its commands run, its version.

The add-on never imports the toolkit (it lives in another Python, with compiled modules):
every call is a child process. No bpy here.
"""

from __future__ import annotations

import json
import os
import shutil

from ..background import steps

# What the add-on tells a user who has no toolkit yet (run outside Blender, from a checkout).
INSTALL_COMMAND = 'python3 -m pip install "./[build]"   (in a Hapticut checkout; docs/addon.md)'
# A quick command (version, material table) must answer within this.
QUICK_TIMEOUT_S = 60.0


class ToolkitError(RuntimeError):
    """The toolkit is missing or a command of it failed; the message is for the user."""


def find_toolkit(configured_path: str = "") -> str:
    """The ``hapticut`` executable: the configured path, else the one on PATH."""
    if configured_path:
        path = os.path.abspath(os.path.expanduser(configured_path))
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
        raise ToolkitError(
            f"the toolkit path {path!r} is not an executable; install with: {INSTALL_COMMAND}"
        )
    found = shutil.which("hapticut")
    if not found:
        raise ToolkitError(
            f"the hapticut toolkit is not on PATH; install it with: {INSTALL_COMMAND}"
        )
    return found


def child_environment(**extra: str) -> dict[str, str]:
    """The environment for a toolkit child: Blender's own Python settings removed (the
    toolkit runs in its own Python), extra entries added."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONHOME", "PYTHONPATH")}
    env.update(extra)
    return env


def last_error_line(text: str) -> str:
    """The last non-empty line of a child's stderr (what the user sees of a failure)."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else "(no error message)"


def quick_steps(
    executable: str, *args: str, timeout_s: float = QUICK_TIMEOUT_S
) -> steps.Steps[str]:
    """A short toolkit command's stdout, as steps; ToolkitError with its last error line on
    failure (the child is killed after timeout_s)."""
    try:
        done = yield from steps.child(
            [executable, *args], timeout_s, f"asking the toolkit ({args[0]})", child_environment()
        )
    except (OSError, steps.ChildTimeoutError) as error:
        raise ToolkitError(f"hapticut {' '.join(args)}: {error}") from None
    if done.returncode != 0:
        line = last_error_line(done.stderr)
        # The toolkit's own messages start with "hapticut <command>:" already.
        raise ToolkitError(line if line.startswith("hapticut") else f"hapticut {args[0]}: {line}")
    return done.stdout


def json_steps(
    executable: str, command: str, timeout_s: float = QUICK_TIMEOUT_S
) -> steps.Steps[dict]:
    """``hapticut <command> --json``, parsed, as steps; ToolkitError when it fails or prints
    no JSON."""
    text = yield from quick_steps(executable, command, "--json", timeout_s=timeout_s)
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise ToolkitError(f"hapticut {command} --json printed no JSON ({error})") from None


def version_steps(executable: str) -> steps.Steps[str]:
    """The installed toolkit's version (``hapticut --version`` prints "hapticut <version>")."""
    text = yield from quick_steps(executable, "--version")
    return text.strip().removeprefix("hapticut ").strip()
