//! The keys each table of a scene file allows: the fixed core of docs/scene-format.md and our own
//! tables (hairs, walls, the sweep, the start, the contact solver, the sensors, and a follow
//! scene's robot, controller and run).

/// Keys allowed at the top level of a scene file.
pub const TOP_LEVEL_KEYS: &[&str] = &[
    "antenna",
    "base",
    "tip_load",
    "tip_pin",
    "solver",
    "walls",
    "sweep",
    "start",
    "contact",
    "sensors",
    "robot",
    "controller",
    "follow",
];
/// Keys allowed in `[antenna]`.
pub const ANTENNA_KEYS: &[&str] = &[
    "links",
    "link_length_m",
    "link_lengths_m",
    "base_angle_deg",
    "joint_limits_deg",
    "rest_angles_deg",
    "stiffness",
    "hairs",
];
/// Keys allowed in `[antenna.stiffness]`.
pub const STIFFNESS_KEYS: &[&str] = &[
    "profile",
    "min_n_m_per_rad",
    "max_n_m_per_rad",
    "values_n_m_per_rad",
];
/// Keys allowed in `[antenna.hairs]`.
pub const HAIRS_KEYS: &[&str] = &[
    "links",
    "direction",
    "side",
    "length_m",
    "open_angle_deg",
    "pivot_from_distal_end_m",
    "lateral_offset_m",
    "preload_n_m",
    "stiffness_n_m_per_rad",
    "root_stiffness_n_m_per_rad",
];
/// Keys allowed in `[base]`.
pub const BASE_KEYS: &[&str] = &["position_m"];
/// Keys allowed in `[tip_load]`.
pub const TIP_LOAD_KEYS: &[&str] = &["force_n"];
/// Keys allowed in `[tip_pin]`.
pub const TIP_PIN_KEYS: &[&str] = &["position_m"];
/// Keys allowed in `[solver]`.
pub const SOLVER_KEYS: &[&str] = &["tolerance", "max_iterations", "initial"];
/// Keys allowed in each `[[walls]]` table (which of the shape keys apply depends on `shape`).
pub const WALL_KEYS: &[&str] = &[
    "shape",
    "solid",
    "point_m",
    "angle_deg",
    "vertices_m",
    "points_file",
    "amplitude_m",
    "frequency_per_m",
    "phase_deg",
    "surface",
    "mu",
    "hold_shear_n",
    "hold_tension_n",
    "zones_along",
    "zones",
];
/// Keys allowed in each `[[walls.zones]]` table.
pub const ZONE_KEYS: &[&str] = &["from_m", "surface", "mu", "hold_shear_n", "hold_tension_n"];
/// Keys allowed in `[sweep]`.
pub const SWEEP_KEYS: &[&str] = &["velocity_m_per_s", "duration_s", "step_s"];
/// Keys allowed in `[start]` (which apply depends on `placement`).
pub const START_KEYS: &[&str] = &[
    "placement",
    "angles_deg",
    "wall",
    "distance_m",
    "along_m",
    "steps",
    "ahead_m",
    "shape",
];
/// Keys allowed in `[contact]`.
pub const CONTACT_KEYS: &[&str] = &[
    "tolerance_m",
    "max_iterations",
    "max_substep_depth",
    "jump_deg",
    "margin_m",
];
/// Keys allowed in `[sensors]`.
pub const SENSORS_KEYS: &[&str] = &[
    "angle_noise_counts",
    "offset_counts",
    "gain_error",
    "touch_threshold_n",
    "touch_debounce_samples",
    "sample_rate_hz",
    "seed",
    "hair_tip_points",
];
/// Keys allowed in `[robot]` (a follow scene; which body keys apply depends on `body`).
pub const ROBOT_KEYS: &[&str] = &[
    "speed_m_per_s",
    "body",
    "inertia_kg_m2",
    "damping_n_m_s_per_rad",
    "max_turn_rate_deg_per_s",
    "max_turn_accel_deg_per_s2",
    "footprint_m",
    "mount_m",
    "mount_angle_deg",
    "wall_side",
    "antenna_loads_body",
];
/// Keys allowed in `[controller]` (a follow scene; which apply depends on `estimator` and
/// on `[robot] body`).
pub const CONTROLLER_KEYS: &[&str] = &[
    "estimator",
    "window_s",
    "preview_m",
    "setpoint_m",
    "kp_n",
    "kd_n_s",
    "kp_rad_per_s_per_m",
    "kd_rad_per_m",
    "delay_s",
    "search_turn_rate_deg_per_s",
];
/// Keys allowed in `[follow]` (a follow scene).
pub const FOLLOW_KEYS: &[&str] = &[
    "duration_s",
    "step_s",
    "pose_m",
    "heading_deg",
    "lost_after_s",
    "lost_beyond_m",
    "settling_window_m",
    "settling_band_m",
    "antenna_step_m",
];

/// Every table with its allowed keys, for naming the table of an unknown key.
pub(crate) const TABLES: &[(&str, &[&str])] = &[
    ("the top level", TOP_LEVEL_KEYS),
    ("[antenna]", ANTENNA_KEYS),
    ("[antenna.stiffness]", STIFFNESS_KEYS),
    ("[antenna.hairs]", HAIRS_KEYS),
    ("[base]", BASE_KEYS),
    ("[tip_load]", TIP_LOAD_KEYS),
    ("[tip_pin]", TIP_PIN_KEYS),
    ("[solver]", SOLVER_KEYS),
    ("[[walls]]", WALL_KEYS),
    ("[[walls.zones]]", ZONE_KEYS),
    ("[sweep]", SWEEP_KEYS),
    ("[start]", START_KEYS),
    ("[contact]", CONTACT_KEYS),
    ("[sensors]", SENSORS_KEYS),
    ("[robot]", ROBOT_KEYS),
    ("[controller]", CONTROLLER_KEYS),
    ("[follow]", FOLLOW_KEYS),
];

/// The keys the parser itself requires (every other key is optional or checked after
/// parsing), with their tables: a "missing field" from the parser names its table from here.
pub(crate) const REQUIRED_KEYS: &[(&str, &str)] = &[
    ("the top level", "antenna"),
    ("[antenna]", "links"),
    ("[tip_load]", "force_n"),
    ("[tip_pin]", "position_m"),
];
