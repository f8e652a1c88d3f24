"""One operator per module; ``classes`` in registration order."""

from .bake_recording import HAPTICUT_OT_bake_recording
from .cancel_build import HAPTICUT_OT_cancel_build
from .cancel_job import HAPTICUT_OT_cancel_job
from .check_scene import HAPTICUT_OT_check_scene
from .check_toolkit import HAPTICUT_OT_check_toolkit
from .clear_bake import HAPTICUT_OT_clear_bake
from .engage_servo import HAPTICUT_OT_engage_servo
from .export_scene import HAPTICUT_OT_export_scene
from .fork_work_folder import HAPTICUT_OT_fork_work_folder
from .go_live import HAPTICUT_OT_go_live
from .import_scene import HAPTICUT_OT_import_scene
from .open_servo_log import HAPTICUT_OT_open_servo_log
from .record_live import HAPTICUT_OT_record_live
from .refresh_devices import HAPTICUT_OT_refresh_devices
from .reset_cuts import HAPTICUT_OT_reset_cuts
from .set_custom_material import HAPTICUT_OT_set_custom_material
from .set_cutting_edge import HAPTICUT_OT_set_cutting_edge
from .simulate_stroke import HAPTICUT_OT_simulate_stroke
from .start_servo import HAPTICUT_OT_start_servo
from .stop_servo import HAPTICUT_OT_stop_servo
from .tetrahedralize import HAPTICUT_OT_tetrahedralize
from .wait import HAPTICUT_OT_wait

classes = (
    HAPTICUT_OT_check_toolkit,
    HAPTICUT_OT_check_scene,
    HAPTICUT_OT_set_custom_material,
    HAPTICUT_OT_set_cutting_edge,
    HAPTICUT_OT_tetrahedralize,
    HAPTICUT_OT_cancel_build,
    HAPTICUT_OT_cancel_job,
    HAPTICUT_OT_fork_work_folder,
    HAPTICUT_OT_export_scene,
    HAPTICUT_OT_import_scene,
    HAPTICUT_OT_refresh_devices,
    HAPTICUT_OT_start_servo,
    HAPTICUT_OT_stop_servo,
    HAPTICUT_OT_go_live,
    HAPTICUT_OT_engage_servo,
    HAPTICUT_OT_reset_cuts,
    HAPTICUT_OT_record_live,
    HAPTICUT_OT_simulate_stroke,
    HAPTICUT_OT_bake_recording,
    HAPTICUT_OT_clear_bake,
    HAPTICUT_OT_open_servo_log,
    HAPTICUT_OT_wait,
)
