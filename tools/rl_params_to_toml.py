#!/usr/bin/python3
"""Turn robot_localization EKF node parameters (YAML) into an rtfuse TOML config.

A file with robot_localization's dual-EKF set-up (an EKF in odom, one in map,
and navsat_transform_node) becomes one config with two filter instances: the
odom node as the first ([filter], [[sensor]]), the map node as an
[[instance]] whose navsat_transform output sensor (odomN on odometry/gps)
becomes a navsat sensor on the receiver's fix with the transform's
parameters. Each instance takes a short name: --name NODE=NAME, else
`..._odom` -> local and `..._map` -> global (by world_frame when the node's
name says neither).

Reads ROS 2 parameter files (`node: {ros__parameters: {...}}`) and ROS 1
rosparam files (flat, or `node_name: {...}`). Everything robot_localization
would use and rtfuse understands is carried over under the same name (see
docs/configuration.md); everything else is listed on stderr, and in the
output's header comment, so nothing disappears silently.

Where robot_localization quietly changes a setting at start-up, the converter
applies the same change and says so: config entries a sensor type cannot
provide are cleared, `differential` wins over `relative`, sensors after a gap
in the numbering (odom0, odom2) are ignored, and sensors with no update
variable left are not subscribed.
"""

import argparse
import math
import re
import sys
from collections import OrderedDict
from pathlib import Path

EXIT_OK = 0
EXIT_ERROR = 2

STATE = ["x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz",
         "vroll", "vpitch", "vyaw", "ax", "ay", "az"]
N = len(STATE)

# robot_localization's default rate; rtfuse's own default (200 Hz) differs, so
# a file without `frequency` must say 30 explicitly to behave the same.
RL_DEFAULT_FREQUENCY = 30.0

# Parameter prefix -> rtfuse sensor type, in the order robot_localization
# subscribes them.
SENSOR_PREFIXES = OrderedDict([("odom", "odometry"), ("pose", "pose"),
                               ("twist", "twist"), ("imu", "imu")])
SENSOR_RE = re.compile(r"^(odom|pose|twist|imu)(\d+)(_.*)?$")

# State entries each message type can carry; robot_localization zeroes the
# rest of the update vector, rtfuse rejects them, so they are cleared here.
PROVIDES = {
    "odometry": set(range(0, 12)),
    "pose": set(range(0, 6)),
    "twist": set(range(6, 12)),
    "imu": {3, 4, 5, 9, 10, 11, 12, 13, 14},
}

# Per-type parameter suffix -> (rtfuse key, kind). The names are
# robot_localization's own: pose and twist sensors have a single
# `_rejection_threshold`, twist sensors have no differential/relative.
SENSOR_PARAMS = {
    "odometry": {
        "_config": ("config", "mask"),
        "_differential": ("differential", "bool"),
        "_relative": ("relative", "bool"),
        "_queue_size": ("queue_size", "int"),
        "_pose_rejection_threshold": ("pose_rejection_threshold", "float"),
        "_twist_rejection_threshold": ("twist_rejection_threshold", "float"),
    },
    "pose": {
        "_config": ("config", "mask"),
        "_differential": ("differential", "bool"),
        "_relative": ("relative", "bool"),
        "_queue_size": ("queue_size", "int"),
        "_rejection_threshold": ("pose_rejection_threshold", "float"),
    },
    "twist": {
        "_config": ("config", "mask"),
        "_queue_size": ("queue_size", "int"),
        "_rejection_threshold": ("twist_rejection_threshold", "float"),
    },
    "imu": {
        "_config": ("config", "mask"),
        "_differential": ("differential", "bool"),
        "_relative": ("relative", "bool"),
        "_queue_size": ("queue_size", "int"),
        "_pose_rejection_threshold": ("pose_rejection_threshold", "float"),
        "_twist_rejection_threshold": ("twist_rejection_threshold", "float"),
        "_linear_acceleration_rejection_threshold":
            ("linear_acceleration_rejection_threshold", "float"),
        "_remove_gravitational_acceleration":
            ("remove_gravitational_acceleration", "bool"),
    },
}
SENSOR_KEY_ORDER = ["config", "differential", "relative", "queue_size",
                    "pose_rejection_threshold", "twist_rejection_threshold",
                    "linear_acceleration_rejection_threshold",
                    "remove_gravitational_acceleration"]

# robot_localization sensor parameters rtfuse has no equivalent for.
SENSOR_UNSUPPORTED = {
    "_nodelay": "TCP_NODELAY of a ROS subscription; LCM has no such option",
    "_pose_use_child_frame": "not supported by rtfuse",
}

# [filter] keys, in docs/configuration.md order, with their kind.
FILTER_PARAMS = OrderedDict([
    ("frequency", "float"),
    ("sensor_timeout", "float"),
    ("two_d_mode", "bool"),
    ("world_frame", "str"),
    ("odom_frame", "str"),
    ("base_link_frame", "str"),
    ("map_frame", "str"),
    ("process_noise_covariance", "matrix"),
    ("initial_estimate_covariance", "matrix"),
    ("dynamic_process_noise_covariance", "bool"),
    ("initial_state", "vector"),
    ("smooth_lagged_data", "bool"),
    ("history_length", "float"),
    ("gravitational_acceleration", "float"),
])
PUBLISH_PARAMS = OrderedDict([("publish_tf", "bool")])

# robot_localization (and ROS) parameters that have no rtfuse counterpart.
UNSUPPORTED = {
    "use_sim_time": "ROS clock; rtfuse replay runs on the log's time",
    "clear_params": "roslaunch option",
    "filter_type": "rtfuse is an EKF only",
    "alpha": "UKF parameter", "kappa": "UKF parameter", "beta": "UKF parameter",
    "print_diagnostics": "rtfuse always publishes diagnostics ([publish] diagnostics_rate)",
    "debug": "no debug file output", "debug_out_file": "no debug file output",
    "publish_acceleration": "acceleration is in the rtfuse/state output",
    "permit_corrected_publication": "not supported",
    "transform_time_offset": "not supported", "transform_timeout": "not supported",
    "tf_prefix": "not supported; name frames in full",
    "base_link_frame_output": "not supported",
    "reset_on_time_jump": "rtfuse's clock is monotonic",
    "predict_to_current_time": "not supported",
    "silent_tf_failure": "no tf lookups; static transforms come from config",
    "disabled_at_startup": "not supported",
    "use_control": "control input not supported",
    "stamped_control": "control input not supported",
    "control_timeout": "control input not supported",
    "control_config": "control input not supported",
    "acceleration_limits": "control input not supported",
    "acceleration_gains": "control input not supported",
    "deceleration_limits": "control input not supported",
    "deceleration_gains": "control input not supported",
}

# Keys that mark a navsat_transform node, which also has `frequency` and is
# often in the same file as the EKFs.
NAVSAT_KEYS = {"magnetic_declination_radians", "yaw_offset", "zero_altitude",
               "broadcast_utm_transform", "broadcast_cartesian_transform",
               "use_odometry_yaw", "wait_for_datum", "datum"}


class ParamError(Exception):
    pass


# --------------------------------------------------------------------------
# YAML -> nodes

def flatten(params, prefix=""):
    """ROS 2 nests dotted parameter names as maps; flatten them back."""
    out = OrderedDict()
    for k, v in params.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


def find_nodes(doc):
    """[(name, params, style)] for every node in a parameter file."""
    if not isinstance(doc, dict):
        raise ParamError("expected a YAML mapping at the top level")
    nodes = []

    def has_ros2(d):
        return any(isinstance(v, dict) and
                   ("ros__parameters" in v or has_ros2(v)) for v in d.values())

    if has_ros2(doc):
        def walk2(d, path):
            for k, v in d.items():
                if not isinstance(v, dict):
                    continue
                if isinstance(v.get("ros__parameters"), dict):
                    nodes.append(("/".join(path + [str(k)]),
                                  flatten(v["ros__parameters"]), "ROS 2"))
                else:
                    walk2(v, path + [str(k)])
        walk2(doc, [])
        return nodes

    # ROS 1: a mapping is a namespace; its scalar/list entries are the
    # parameters of the node of that name.
    def walk1(d, path):
        own = OrderedDict((k, v) for k, v in d.items() if not isinstance(v, dict))
        if own:
            nodes.append(("/".join(path), own, "ROS 1"))
        for k, v in d.items():
            if isinstance(v, dict):
                walk1(v, path + [str(k)])
    walk1(doc, [])
    return nodes


def display(name):
    return name if name else "(top level)"


def is_ekf(params):
    keys = set(params)
    if keys & NAVSAT_KEYS:
        return False
    return "frequency" in keys or any(
        SENSOR_RE.match(k) and SENSOR_RE.match(k).group(3) is None for k in keys)


def select_node(nodes, wanted):
    if not nodes:
        raise ParamError("no parameters found")
    if wanted is not None:
        w = wanted.strip("/")
        hits = [n for n in nodes if n[0].strip("/") == w]
        if not hits:
            hits = [n for n in nodes if n[0].strip("/").split("/")[-1] == w]
        if len(hits) == 1:
            return hits[0]
        names = ", ".join(display(n[0]) for n in (hits or nodes))
        if hits:
            raise ParamError(f"--node {wanted} is ambiguous: {names}")
        raise ParamError(f"no node {wanted!r}; nodes in the file: {names}")
    ekf = [n for n in nodes if is_ekf(n[1])]
    if len(ekf) == 1:
        return ekf[0]
    if not ekf:
        raise ParamError("no EKF node (one with `frequency` or odomN/poseN/"
                         "twistN/imuN parameters); nodes in the file: " +
                         ", ".join(display(n[0]) for n in nodes))
    raise ParamError("several EKF nodes, choose one with --node: " +
                     ", ".join(display(n[0]) for n in ekf))


# --------------------------------------------------------------------------
# value checks

def _is_num(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def as_float(key, v):
    if not _is_num(v):
        raise ParamError(f"{key}: expected a number, got {v!r}")
    try:
        return float(v)
    except OverflowError:
        raise ParamError(f"{key}: {v} is out of range for a double") from None


def as_bool(key, v):
    if not isinstance(v, bool):
        raise ParamError(f"{key}: expected true or false, got {v!r}")
    return v


def as_int(key, v):
    if isinstance(v, float) and v.is_integer():
        v = int(v)
    if not isinstance(v, int) or isinstance(v, bool):
        raise ParamError(f"{key}: expected an integer, got {v!r}")
    return v


def as_str(key, v):
    if not isinstance(v, str) or not v:
        raise ParamError(f"{key}: expected a non-empty string, got {v!r}")
    return v


def as_list(key, v, n, conv):
    if isinstance(v, list) and v and all(isinstance(r, list) for r in v):
        v = [x for r in v for x in r]  # accept a matrix written as rows
    if not isinstance(v, list):
        raise ParamError(f"{key}: expected a list of {n} values, got {v!r}")
    if len(v) != n:
        raise ParamError(f"{key}: expected {n} values, got {len(v)}")
    return [conv(f"{key}[{i}]", x) for i, x in enumerate(v)]


def as_matrix(key, v):
    vals = as_list(key, v, N * N, as_float)
    diagonal = all(vals[i * N + j] == 0.0
                   for i in range(N) for j in range(N) if i != j)
    return [vals[i * N + i] for i in range(N)] if diagonal else vals


CONVERT = {
    "float": as_float, "bool": as_bool, "int": as_int, "str": as_str,
    "matrix": as_matrix,
    "vector": lambda k, v: as_list(k, v, N, as_float),
    "mask": lambda k, v: as_list(k, v, N, as_bool),
}


# --------------------------------------------------------------------------
# conversion

class Result:
    def __init__(self):
        self.filter = OrderedDict()
        self.publish = OrderedDict()
        self.sensors = []            # OrderedDicts
        self.static_tfs = []         # OrderedDicts
        self.not_carried = []        # (key, value, reason)
        self.unknown = []            # (key, value)
        self.notes = []              # adjustments made as robot_localization does
        self.defaults = []           # values emitted because rtfuse's default differs


def convert_params(params):
    res = Result()
    used = set()

    for key, kind in FILTER_PARAMS.items():
        if key in params:
            res.filter[key] = CONVERT[kind](key, params[key])
            used.add(key)
    for key, kind in PUBLISH_PARAMS.items():
        if key in params:
            res.publish[key] = CONVERT[kind](key, params[key])
            used.add(key)

    if "frequency" not in res.filter:
        res.filter["frequency"] = RL_DEFAULT_FREQUENCY
        res.defaults.append("frequency = 30.0 (robot_localization's default; "
                            "rtfuse's own is 200)")
    elif res.filter["frequency"] <= 0:
        raise ParamError(f"frequency: must be > 0, got {res.filter['frequency']}")
    hl = res.filter.get("history_length")
    if hl is not None and hl < 0:
        res.filter["history_length"] = -hl
        res.notes.append(f"history_length {hl} is negative; robot_localization "
                         f"uses its absolute value, so does the output")

    # Sensors: robot_localization subscribes prefix0, prefix1, ... and stops
    # at the first missing index.
    for prefix, stype in SENSOR_PREFIXES.items():
        indices = sorted(int(m.group(2)) for m in map(SENSOR_RE.match, params)
                         if m and m.group(1) == prefix and m.group(3) is None)
        i = 0
        while f"{prefix}{i}" in params:
            name = f"{prefix}{i}"
            s = convert_sensor(name, stype, params, used, res)
            if s is not None:
                res.sensors.append(s)
            i += 1
        for j in indices:
            if j > i:
                keys = [k for k in params
                        if (m := SENSOR_RE.match(k)) and m.group(1) == prefix
                        and int(m.group(2)) == j]
                used.update(keys)
                res.notes.append(
                    f"{prefix}{j} ignored ({', '.join(keys)}): robot_localization "
                    f"stops at the first missing index ({prefix}{i})")

    for key, value in params.items():
        if key in used:
            continue
        m = SENSOR_RE.match(key)
        if key in UNSUPPORTED:
            res.not_carried.append((key, value, UNSUPPORTED[key]))
        elif m and m.group(3) in SENSOR_UNSUPPORTED:
            res.not_carried.append((key, value, SENSOR_UNSUPPORTED[m.group(3)]))
        else:
            res.unknown.append((key, value))
    return res


def convert_sensor(name, stype, params, used, res):
    used.add(name)
    s = OrderedDict()
    s["name"] = name
    s["type"] = stype
    s["channel"] = as_str(name, params[name])
    for suffix, (key, kind) in SENSOR_PARAMS[stype].items():
        pkey = name + suffix
        if pkey in params:
            s[key] = CONVERT[kind](pkey, params[pkey])
            used.add(pkey)
    if "config" not in s:
        # robot_localization's loadUpdateConfig treats a missing vector as all
        # false, which then leaves the sensor unsubscribed.
        s["config"] = [False] * N
    mask = s["config"]
    cleared = [STATE[i] for i in range(N) if mask[i] and i not in PROVIDES[stype]]
    if cleared:
        s["config"] = [mask[i] and i in PROVIDES[stype] for i in range(N)]
        res.notes.append(f"{name}_config: {' '.join(cleared)} cleared: {stype} "
                         f"sensors cannot provide them (robot_localization ignores them)")
    if s.get("differential") and s.get("relative"):
        s["relative"] = False
        res.notes.append(f"{name}: differential and relative both true; "
                         "differential wins, as in robot_localization")
    if "queue_size" in s and not 1 <= s["queue_size"] <= 1024:
        q = min(max(s["queue_size"], 1), 1024)
        res.notes.append(f"{name}_queue_size {s['queue_size']} clamped to {q} "
                         "(rtfuse allows 1-1024)")
        s["queue_size"] = q
    if not any(s["config"]):
        res.notes.append(f"{name} ({s['channel']}) not carried over: no update "
                         "variable is true, robot_localization does not subscribe it")
        return None
    return OrderedDict((k, s[k]) for k in ["name", "type", "channel"] + SENSOR_KEY_ORDER
                       if k in s)


def parse_static_tf(text):
    """tf2 static_transform_publisher's positional forms:
    'x y z yaw pitch roll parent child' or 'x y z qx qy qz qw parent child'."""
    parts = text.split()
    if len(parts) not in (8, 9):
        raise ParamError(f"--static-tf {text!r}: expected 'x y z yaw pitch roll "
                         "parent child' (or 'x y z qx qy qz qw parent child')")
    nums = parts[:-2]
    try:
        vals = [float(v) for v in nums]
    except ValueError:
        raise ParamError(f"--static-tf {text!r}: {nums} are not all numbers") from None
    if not all(math.isfinite(v) for v in vals):
        raise ParamError(f"--static-tf {text!r}: values must be finite")
    tf = OrderedDict(parent=parts[-2], child=parts[-1], translation=vals[:3])
    if tf["parent"] == tf["child"]:
        raise ParamError(f"--static-tf {text!r}: parent and child are the same frame")
    if len(vals) == 6:
        yaw, pitch, roll = vals[3:6]
        tf["rpy"] = [roll, pitch, yaw]
    else:
        tf["quaternion"] = vals[3:7]
    return tf


# --------------------------------------------------------------------------
# dual EKF + navsat_transform

# robot_localization's values for [filter] keys an EKF node leaves out: an
# rtfuse [[instance]] would otherwise inherit the first instance's.
RL_FILTER_DEFAULTS = OrderedDict([
    ("two_d_mode", False),
    ("process_noise_covariance", [0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025,
                                  0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015]),
    ("initial_estimate_covariance", [1e-9] * N),
    ("dynamic_process_noise_covariance", False),
    ("initial_state", [0.0] * N),
    ("smooth_lagged_data", False),
    ("history_length", 0.0),
    ("gravitational_acceleration", 9.80665),
])
FRAME_KEYS = ("odom_frame", "base_link_frame", "map_frame")
INSTANCE_FILTER_KEYS = ["sensor_timeout"] + list(RL_FILTER_DEFAULTS)

# navsat_transform_node parameters -> the navsat sensor's keys.
NAVSAT_PARAMS = OrderedDict([
    ("magnetic_declination_radians", ("magnetic_declination_radians", "float")),
    ("yaw_offset", ("yaw_offset", "float")),
    ("zero_altitude", ("zero_altitude", "bool")),
    ("use_odometry_yaw", ("use_odometry_yaw", "bool")),
])
NAVSAT_UNSUPPORTED = {
    "frequency": "rtfuse converts every fix in the loop, as it arrives",
    "delay": "no start-up delay: the datum waits for its heading instead",
    "broadcast_utm_transform": "rtfuse uses a local tangent plane at the datum, not UTM",
    "broadcast_cartesian_transform": "rtfuse uses a local tangent plane at the datum, not UTM",
    "broadcast_utm_transform_as_parent_frame": "rtfuse uses a local tangent plane at the datum, not UTM",
    "broadcast_cartesian_transform_as_parent_frame": "rtfuse uses a local tangent plane at the datum, not UTM",
    "publish_filtered_gps": "always published (rtfuse/<instance>/gps/filtered)",
    "transform_timeout": "no tf lookups; the antenna's mounting comes from config",
    "use_local_cartesian": "rtfuse always uses a local tangent plane",
    "wait_for_datum": "a datum = [lat, lon, yaw] key is what waits for it",
    "cartesian_frame_id": "not supported",
    "use_sim_time": "ROS clock; rtfuse replay runs on the log's time",
}
NAVSAT_OUTPUT_TOPIC = "odometry/gps"   # navsat_transform_node's default output
NAVSAT_FIX_TOPIC = "gps/fix"           # ... and its default input


def instance_name(node_name, params, given):
    """The instance's short name: --name, else from the node's name or frame."""
    leaf = node_name.strip("/").split("/")[-1] if node_name else ""
    for key in (node_name.strip("/"), leaf):
        if key in given:
            return given[key]
    if leaf.endswith("_odom"):
        return "local"
    if leaf.endswith("_map"):
        return "global"
    return "global" if params.get("world_frame") == "map" else "local"


def navsat_sensor(res, navsat_params, output_topic, fix_topic):
    """Replaces the map node's sensor on navsat_transform's output by a navsat
    sensor on the fix, carrying the transform's parameters."""
    idx = [i for i, s in enumerate(res.sensors)
           if s["type"] == "odometry" and s["channel"].strip("/") == output_topic.strip("/")]
    if not idx:
        raise ParamError(f"the map EKF fuses no odomN on navsat_transform's output "
                         f"'{output_topic}' (give --navsat-output TOPIC if it is remapped)")
    old = res.sensors[idx[0]]
    s = OrderedDict(name=old["name"], type="navsat", channel=fix_topic)
    mask = old["config"]
    dropped = [STATE[i] for i in range(N) if mask[i] and i > 2]
    s["config"] = [mask[i] and i <= 2 for i in range(N)]
    if dropped:
        res.notes.append(f"{old['name']}: {' '.join(dropped)} cleared: a fix is a position "
                         "(navsat_transform's odometry/gps carries nothing else)")
    if not any(s["config"]):
        raise ParamError(f"{old['name']}_config fuses none of x y z: the fix would be ignored")
    for k in ("queue_size", "pose_rejection_threshold"):
        if k in old:
            s[k] = old[k]
    for k in ("differential", "relative"):
        if old.get(k):
            res.notes.append(f"{old['name']}_{k} dropped: a navsat sensor is absolute")
    for key, (out, kind) in NAVSAT_PARAMS.items():
        if key in navsat_params:
            s[out] = CONVERT[kind](key, navsat_params[key])
    datum = navsat_params.get("datum")
    if navsat_params.get("wait_for_datum") and datum is not None:
        if not isinstance(datum, list) or len(datum) < 3 or not all(_is_num(v) for v in datum[:3]):
            raise ParamError(f"datum: expected [latitude, longitude, yaw, ...], got {datum!r}")
        lat, lon, yaw = (float(v) for v in datum[:3])
        if not (-90 <= lat <= 90 and -180 <= lon <= 180):
            raise ParamError(f"datum: latitude {lat} / longitude {lon} out of range")
        s["datum"] = [lat, lon, yaw]
        s.pop("use_odometry_yaw", None)
    elif not s.get("use_odometry_yaw"):
        s.pop("use_odometry_yaw", None)  # false is the default; the IMU is the source
        # Its imu input: the map EKF's IMU (one fusing yaw first).
        imus = sorted((x for x in res.sensors if x["type"] == "imu"), key=lambda x: not x["config"][5])
        if not imus:
            raise ParamError("navsat_transform takes its heading from an IMU, but the map EKF "
                             "has no IMU sensor: set use_odometry_yaw or a datum")
        s["heading_imu"] = imus[0]["name"]
        res.notes.append(f"{old['name']}: the datum's heading comes from {imus[0]['name']} "
                         f"({imus[0]['channel']}), as navsat_transform's imu input")
    res.notes.append(f"{old['name']}: navsat_transform's output ({old['channel']}) became a navsat "
                     f"sensor on the fix ({fix_topic}); give it frame = <antenna frame> and a "
                     "static transform for the antenna's lever arm")
    for key, value in navsat_params.items():
        if key in NAVSAT_PARAMS or key == "datum":
            continue
        if key in NAVSAT_UNSUPPORTED:
            res.not_carried.append((key, value, NAVSAT_UNSUPPORTED[key]))
        else:
            res.unknown.append((key, value))
    res.sensors[idx[0]] = s


def convert_dual(local, glob, navsat, names, output_topic, fix_topic):
    """(Result of the first instance, Result of the [[instance]], its name)."""
    (lname, lparams, _), (gname, gparams, _) = local, glob
    lres, gres = convert_params(lparams), convert_params(gparams)
    lres.filter["name"] = instance_name(lname, lparams, names)
    gshort = instance_name(gname, gparams, names)
    if gshort == lres.filter["name"]:
        raise ParamError(f"both EKF nodes would be named '{gshort}': give --name NODE=NAME")
    for k in FRAME_KEYS:
        if k in gres.filter and gres.filter[k] != lres.filter.get(k, gres.filter[k]):
            raise ParamError(f"{k}: '{gres.filter[k]}' in {display(gname)} but "
                             f"'{lres.filter[k]}' in {display(lname)}: rtfuse has one set of frames")
        if k in gres.filter:
            lres.filter.setdefault(k, gres.filter[k])
    lf, gf = lres.filter["frequency"], gres.filter["frequency"]
    if gf != lf:
        lres.filter["frequency"] = max(lf, gf)
        lres.notes.append(f"frequency: {lf} Hz ({display(lname)}) and {gf} Hz ({display(gname)}): "
                          f"one loop runs both instances at {max(lf, gf)} Hz")
    # robot_localization's sensor_timeout defaults to 1 / the node's own
    # frequency, which the shared loop rate may no longer be.
    if "sensor_timeout" not in lres.filter and lres.filter["frequency"] != lf:
        lres.filter["sensor_timeout"] = 1.0 / lf
        lres.defaults.append(f"sensor_timeout = 1/{lf} Hz ({display(lname)}'s own frequency)")
    inst = OrderedDict(name=gshort, world_frame=gres.filter.get("world_frame", "odom"))
    if "sensor_timeout" not in gres.filter and ("sensor_timeout" in lres.filter or lres.filter["frequency"] != gf):
        gres.filter["sensor_timeout"] = 1.0 / gf
    for k, v in RL_FILTER_DEFAULTS.items():
        if k not in gres.filter and k in lres.filter:
            gres.filter[k] = v
            gres.defaults.append(f"{k} in {gshort} (robot_localization's default; it would "
                                 f"inherit {lres.filter['name']}'s)")
    for k in INSTANCE_FILTER_KEYS:
        if k in gres.filter:
            inst[k] = gres.filter[k]
    if navsat is not None:
        navsat_sensor(gres, navsat[1], output_topic, fix_topic)
    gres.instance = inst
    return lres, gres


def render_instance(gres):
    L = ["", "[[instance]]"]
    for k, v in gres.instance.items():
        L.append(toml_kv(k, v))
    for s in gres.sensors:
        L.append("")
        L.append("[[instance.sensor]]")
        for k, v in s.items():
            L.append(toml_kv(k, v))
    return L


# --------------------------------------------------------------------------
# TOML output (written by hand: Debian 12's Python has a TOML reader only)

def toml_str(s):
    out = ['"']
    for ch in s:
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def toml_float(v):
    v = float(v)
    if math.isnan(v):
        return "nan"
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return repr(v)  # shortest round-trip form; always has '.' or 'e'


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return toml_float(v)
    if isinstance(v, str):
        return toml_str(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} as TOML")


def toml_array_rows(key, values, per_row):
    """Long arrays one matrix row per line, so they read like the YAML did."""
    if len(values) <= per_row:
        return f"{key} = {toml_value(values)}"
    pad = " " * (len(key) + 4)
    rows = [", ".join(toml_value(x) for x in values[i:i + per_row])
            for i in range(0, len(values), per_row)]
    return f"{key} = [" + (",\n" + pad).join(rows) + "]"


def toml_kv(key, v):
    if isinstance(v, list) and len(v) == N * N:
        return toml_array_rows(key, v, N)
    if isinstance(v, list) and len(v) == N and all(isinstance(x, bool) for x in v):
        return toml_array_rows(key, v, 3)  # config masks: x y z / r p y / ...
    return f"{key} = {toml_value(v)}"


def comment_value(v):
    try:
        text = toml_value(v)
    except TypeError:
        text = repr(v)
    return text if len(text) <= 60 else text[:57] + "..."


def render(res, source, node_name, style, extra=None):
    L = []
    L.append("# rtfuse configuration generated by tools/rl_params_to_toml.py")
    L.append("# from robot_localization parameters: " + source.replace("\n", " "))
    L.append(f"# node: {display(node_name)} ({style} parameter file)")
    L.append("# Schema: docs/configuration.md.")
    for d in res.defaults:
        L.append(f"# default made explicit: {d}")
    for n in res.notes:
        L.append(f"# adjusted: {n}")
    if res.not_carried:
        L.append("# not carried over (no rtfuse equivalent):")
        for k, v, why in res.not_carried:
            L.append(f"#   {k} = {comment_value(v)}  ({why})")
    if res.unknown:
        L.append("# not carried over (not robot_localization EKF parameters):")
        for k, v in res.unknown:
            L.append(f"#   {k} = {comment_value(v)}")
    L.append("")
    L.append("[filter]")
    if "name" in res.filter:
        res.filter.move_to_end("name", last=False)
    for k, v in res.filter.items():
        L.append(toml_kv(k, v))
    if res.publish:
        L.append("")
        L.append("[publish]")
        for k, v in res.publish.items():
            L.append(toml_kv(k, v))
    for s in res.sensors:
        L.append("")
        L.append("[[sensor]]")
        for k, v in s.items():
            L.append(toml_kv(k, v))
    if extra is not None:
        if extra.not_carried or extra.unknown:
            at = next(i for i, line in enumerate(L) if line == "")
            lines = [f"#   {k} = {comment_value(v)}  ({why})" for k, v, why in extra.not_carried]
            lines += [f"#   {k} = {comment_value(v)}  (not a robot_localization parameter)" for k, v in extra.unknown]
            L[at:at] = [f"# not carried over from {extra.instance['name']}'s nodes:"] + lines
        for d in extra.defaults:
            L.insert(4, f"# default made explicit: {d}")
        for n in extra.notes:
            L.insert(4, f"# adjusted: {n}")
        L += render_instance(extra)
    for tf in res.static_tfs:
        L.append("")
        L.append("[[static_transform]]")
        for k, v in tf.items():
            L.append(toml_kv(k, v))
    return "\n".join(L) + "\n"


def report(res, node_name, err):
    if res.not_carried:
        print(f"parameters of {display(node_name)} not carried over "
              "(no rtfuse equivalent):", file=err)
        for k, v, why in res.not_carried:
            print(f"  {k} = {comment_value(v)}: {why}", file=err)
    if res.unknown:
        print("parameters not carried over (not robot_localization EKF "
              "parameters):", file=err)
        for k, v in res.unknown:
            print(f"  {k} = {comment_value(v)}", file=err)
    for d in res.defaults:
        print(f"note: {d}", file=err)
    for n in res.notes:
        print(f"note: {n}", file=err)


def _loader():
    import yaml

    class Loader(yaml.SafeLoader):
        pass

    # PyYAML follows YAML 1.1, where an unquoted 1e-9 (no dot) is a string;
    # ROS 2's parameter parser and YAML 1.2 read it as a number, and RL
    # files use that spelling, so resolve floats the YAML 1.2 way.
    Loader.add_implicit_resolver(
        "tag:yaml.org,2002:float",
        re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                    |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                    |[-+]?\.(?:inf|Inf|INF)
                    |\.(?:nan|NaN|NAN))$""", re.X),
        list("-+0123456789."))
    return yaml, Loader


def dual_nodes(nodes):
    """(odom EKF, map EKF, navsat node or None) when the file holds
    robot_localization's dual-EKF set-up, else None."""
    ekf = [n for n in nodes if is_ekf(n[1])]
    if len(ekf) != 2:
        return None
    in_map = [n for n in ekf if n[1].get("world_frame") == "map"]
    if len(in_map) != 1:
        return None
    local = next(n for n in ekf if n is not in_map[0])
    navsat = [n for n in nodes if set(n[1]) & NAVSAT_KEYS]
    if len(navsat) > 1:
        raise ParamError("several navsat_transform nodes: " + ", ".join(display(n[0]) for n in navsat))
    return local, in_map[0], (navsat[0] if navsat else None)


def convert_file(yaml_path, node=None, static_tfs=(), err=sys.stderr, names=None,
                 navsat_output=NAVSAT_OUTPUT_TOPIC, fix_topic=NAVSAT_FIX_TOPIC):
    """Returns (toml_text, Result, node_name)."""
    yaml, Loader = _loader()
    path = Path(yaml_path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise ParamError(f"cannot read {path}: {e.strerror}") from None
    try:
        # ROS 1 files may hold several documents (rosparam dump); merge them.
        docs = [d for d in yaml.load_all(text, Loader=Loader) if d is not None]
    except yaml.YAMLError as e:
        raise ParamError(f"{path}: invalid YAML: {e}") from None
    doc = OrderedDict()
    for d in docs:
        if not isinstance(d, dict):
            raise ParamError(f"{path}: expected a YAML mapping, got {type(d).__name__}")
        doc.update(d)
    try:
        nodes = find_nodes(doc)
        dual = dual_nodes(nodes) if node is None else None
        if dual is not None:
            local, glob, navsat = dual
            res, gres = convert_dual(local, glob, navsat, names or {}, navsat_output, fix_topic)
            res.static_tfs = [parse_static_tf(t) for t in static_tfs]
            name = local[0]
            report(res, local[0], err)
            report(gres, glob[0], err)
            out = render(res, str(path), f"{display(local[0])}, {display(glob[0])}"
                         + (f" and {display(navsat[0])}" if navsat else ""), local[2], gres)
            res.instances = [res.filter["name"], gres.instance["name"]]
            res.sensors = res.sensors + gres.sensors
            return out, res, name
        name, params, style = select_node(nodes, node)
        res = convert_params(params)
        if names:
            res.filter["name"] = instance_name(name, params, names)
        res.static_tfs = [parse_static_tf(t) for t in static_tfs]
    except ParamError as e:
        raise ParamError(f"{path}: {e}") from None
    report(res, name, err)
    return render(res, str(path), name, style), res, name


def main(argv=None):
    p = argparse.ArgumentParser(
        description="Convert robot_localization EKF parameters (ROS 1 or ROS 2 "
                    "YAML) into an rtfuse TOML configuration.",
        epilog="Parameters that cannot be carried over are listed on stderr "
               "and in the output's header. Exit status: 0 on success, 2 on "
               "any error.")
    p.add_argument("params", metavar="PARAMS.yaml")
    p.add_argument("-o", "--output", metavar="OUT.toml", required=True,
                   help="TOML file to write ('-' for stdout)")
    p.add_argument("--node", metavar="NAME",
                   help="node to convert when the file holds several EKF nodes")
    p.add_argument("--static-tf", metavar='"X Y Z YAW PITCH ROLL PARENT CHILD"',
                   action="append", default=[],
                   help="a static transform in tf2 static_transform_publisher's "
                        "argument order (repeatable); 'x y z qx qy qz qw parent "
                        "child' is accepted too")
    p.add_argument("--name", metavar="NODE=NAME", action="append", default=[],
                   help="the filter instance's short name for an EKF node (repeatable; default: "
                        "..._odom -> local, ..._map -> global)")
    p.add_argument("--navsat-output", metavar="TOPIC", default=NAVSAT_OUTPUT_TOPIC,
                   help="navsat_transform's output topic as the map EKF subscribes it "
                        f"(default {NAVSAT_OUTPUT_TOPIC})")
    p.add_argument("--fix-topic", metavar="TOPIC", default=NAVSAT_FIX_TOPIC,
                   help=f"the receiver's NavSatFix topic (default {NAVSAT_FIX_TOPIC})")
    args = p.parse_args(argv)
    names = {}
    for item in args.name:
        node_name, sep, short = item.partition("=")
        if not sep or not node_name or not re.fullmatch(r"[a-z0-9_]{1,15}", short):
            print(f"rl_params_to_toml: error: --name {item!r}: expected NODE=NAME, NAME 1 to 15 "
                  "characters of a-z, 0-9 and _", file=sys.stderr)
            return EXIT_ERROR
        names[node_name.strip("/")] = short
    try:
        text, res, name = convert_file(args.params, args.node, args.static_tf, names=names,
                                       navsat_output=args.navsat_output, fix_topic=args.fix_topic)
    except ParamError as e:
        print(f"rl_params_to_toml: error: {e}", file=sys.stderr)
        return EXIT_ERROR
    if args.output == "-":
        sys.stdout.write(text)
    else:
        try:
            Path(args.output).write_text(text, encoding="utf-8")
        except OSError as e:
            print(f"rl_params_to_toml: error: cannot write {args.output}: "
                  f"{e.strerror}", file=sys.stderr)
            return EXIT_ERROR
        instances = getattr(res, "instances", None)
        what = (f"instances {' and '.join(instances)}" if instances else f"node {display(name)}")
        print(f"wrote {args.output}: {what}, "
              f"{len(res.sensors)} sensor(s), "
              f"{len(res.static_tfs)} static transform(s)", file=sys.stderr)
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
