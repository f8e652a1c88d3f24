"""The add-on's tests run inside the bpy module (background mode), in their own pytest
process (tests/run_all.sh): bpy cannot be imported twice nor next to the other suites'
compiled modules without risk."""

import pytest

bpy = pytest.importorskip("bpy")


@pytest.fixture(scope="session")
def addon():
    import blender_scene

    # Yields nothing: preferences objects die with a re-registration; read them from context.
    blender_scene.enable_addon()
    yield
    blender_scene.disable_addon()


@pytest.fixture
def data_home(tmp_path, monkeypatch):
    """The user's data folder (where work folders go) inside the test's temporary directory."""
    home = tmp_path / "data"
    monkeypatch.setenv("XDG_DATA_HOME", str(home))
    return home
