import os

# Headless pictures: EGL for pyrender, Agg for matplotlib. Set before anything imports them.
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
os.environ.setdefault("MPLBACKEND", "Agg")
