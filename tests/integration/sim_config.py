"""config/sim.toml's text, edited the way the integration tests need it."""


def without_camera(text):
    """The robot without its stereo camera: the [camera] table, the [vo]
    table of the visual odometry that runs on it, and the odometry's
    [[sensor]] (the last table of the file, after its comment)."""
    for table in ("\n[camera]\n", "\n[vo]\n"):
        at = text.index(table)
        text = text[:at + 1] + text[text.index("\n[", at + 1) + 1:]
    text = text[:text.index("# Visual odometry: the camera")]
    if 'source = "stereo_vo"' in text or "\n[vo]\n" in text or "\n[camera]\n" in text:
        raise ValueError("config/sim.toml's camera tables are not where sim_config expects them")
    return text
