"""config/sim.toml's text, edited the way the integration tests need it."""


def without_camera(text):
    """The robot without its stereo camera: the [camera] table, the [vo]
    and [mapping] tables of the visual odometry and the mapper that run on
    it, and the odometry's [[sensor]] (the last table of the file, after its
    comment)."""
    for table in ("\n[camera]\n", "\n[vo]\n", "\n[mapping]\n"):
        at = text.index(table)
        text = text[:at + 1] + text[text.index("\n[", at + 1) + 1:]
    text = text[:text.index("# Visual odometry: the camera")]
    if 'source = "stereo_vo"' in text or any(t in text for t in ("\n[vo]\n", "\n[camera]\n", "\n[mapping]\n")):
        raise ValueError("config/sim.toml's camera tables are not where sim_config expects them")
    return text
