"""The camera over a shot: its pose and lens as keys where they change (one per frame)."""

ANIMATABLE = ("position", "look_at", "up", "fov", "aperture", "focus_distance")


def add(camera, samples):
    """Keys `camera` (the first frame's entry) with [(frame, entry)] where a value changes."""
    for key in ANIMATABLE:
        values = [(f, c.get(key)) for f, c in samples]
        if key in camera and any(v != values[0][1] for _, v in values):
            camera[key] = {"keys": [[f, v] for f, v in values], "interpolation": "linear"}
    if any(c["resolution"] != camera["resolution"] for _, c in samples):
        raise ValueError("the resolution changes over the animation: render the frames apart")
