"""Reading, cleaning, writing and drawing 2D pose tracks (numpy + OpenCV only).

Video I/O (``pose_io.video``), drawing (``pose_io.draw``) and MediaPipe extraction (``pose_io.extract``)
import OpenCV or ffmpeg and are not re-exported here, so importing ``pose_io`` stays light.
"""

from pose_io.clean import GapReport, fill_gaps, smooth
from pose_io.errors import InputError
from pose_io.layouts import BODY15, BODY25, COCO17, COCO18, LAYOUTS, MEDIAPIPE33, JointLayout, get_layout
from pose_io.people import Detections, follow_person
from pose_io.readers import read_detections, read_track, read_track_summary
from pose_io.resample import resample
from pose_io.track import PoseTrack
from pose_io.writers import write_track

__all__ = [
    "BODY15", "BODY25", "COCO17", "COCO18", "LAYOUTS", "MEDIAPIPE33", "Detections", "GapReport", "InputError",
    "JointLayout", "PoseTrack", "fill_gaps", "follow_person", "get_layout", "read_detections", "read_track",
    "read_track_summary", "resample", "smooth", "write_track",
]
