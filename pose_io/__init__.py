"""Reading, cleaning, writing and drawing 2D pose tracks (numpy + OpenCV only)."""

from pose_io.errors import InputError
from pose_io.layouts import BODY15, BODY25, COCO17, COCO18, LAYOUTS, MEDIAPIPE33, JointLayout, get_layout
from pose_io.track import PoseTrack

__all__ = [
    "BODY15", "BODY25", "COCO17", "COCO18", "LAYOUTS", "MEDIAPIPE33", "InputError", "JointLayout", "PoseTrack",
    "get_layout",
]
