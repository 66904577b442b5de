"""Performance cloning: a pose-to-frame generator driven by retargeted poses, its CLI, reports and demo."""

__version__ = "0.1.0"
