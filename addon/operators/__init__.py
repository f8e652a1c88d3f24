"""One operator per module; ``classes`` in registration order."""

from .cancel_build import HAPTICUT_OT_cancel_build
from .check_scene import HAPTICUT_OT_check_scene
from .check_toolkit import HAPTICUT_OT_check_toolkit
from .export_scene import HAPTICUT_OT_export_scene
from .import_scene import HAPTICUT_OT_import_scene
from .set_custom_material import HAPTICUT_OT_set_custom_material
from .set_cutting_edge import HAPTICUT_OT_set_cutting_edge
from .tetrahedralize import HAPTICUT_OT_tetrahedralize

classes = (
    HAPTICUT_OT_check_toolkit,
    HAPTICUT_OT_check_scene,
    HAPTICUT_OT_set_custom_material,
    HAPTICUT_OT_set_cutting_edge,
    HAPTICUT_OT_tetrahedralize,
    HAPTICUT_OT_cancel_build,
    HAPTICUT_OT_export_scene,
    HAPTICUT_OT_import_scene,
)
