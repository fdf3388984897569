//! What is drawn: the chain's geometry ([`ChainModel`]), one instant of its state
//! ([`ChainPose`]) and an estimated wall ([`EstimatedWall`]).

use crate::stream::RigInfo;

/// The chain's fixed geometry and where it sits in the scene frame (`world`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ChainModel {
    /// Every rigid link, the base link first: one more entry than there are segments, m.
    pub link_lengths_m: Vec<f64>,
    /// The base link's angle from the stage's travel with the servo at 0, rad
    /// (counter-clockwise).
    pub base_mount_angle_rad: f64,
    /// The base pivot with the stage at 0, in the scene frame, m.
    pub origin_m: [f64; 2],
    /// The direction of the stage's travel in the scene frame, rad (counter-clockwise from
    /// the scene's x-axis).
    pub travel_angle_rad: f64,
    /// The walls, each a polyline in the scene frame, m (empty on hardware).
    pub walls_m: Vec<Vec<[f64; 2]>>,
}

impl ChainModel {
    /// The chain as the stream's `hello` (and a recording's metadata) describes it: its links
    /// and base mount angle, the base pivot at the scene's origin, the stage travelling along
    /// the scene's x-axis, no walls. `None` when the rig gives no links (daemons before they
    /// were added).
    pub fn from_rig(rig: &RigInfo) -> Option<Self> {
        (!rig.link_lengths_m.is_empty()).then(|| Self {
            link_lengths_m: rig.link_lengths_m.clone(),
            base_mount_angle_rad: rig.base_mount_angle_deg.to_radians(),
            ..Self::default()
        })
    }

    /// The number of segments (jointed links after the base link).
    pub fn segments(&self) -> usize {
        self.link_lengths_m.len().saturating_sub(1)
    }
}

/// The chain at one instant, as the segments, the stage and the servo reported it.
///
/// A `None` is a reading that is missing (a failed read, a device not reporting): the frame
/// it places is left out of [`super::frame_transforms`], so a viewer keeps the last one it
/// was given (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ChainPose<'a> {
    /// When, ns (the time stamp of every message made from it; a recording uses Unix-epoch
    /// nanoseconds, its log time).
    pub t_ns: u64,
    /// The stage's position along its travel, m.
    pub stage_m: Option<f64>,
    /// The servo's angle (added to the base mount angle), rad.
    pub servo_rad: Option<f64>,
    /// One joint angle per segment, base first, rad.
    pub joint_angles_rad: &'a [Option<f64>],
    /// One touch word per segment, base first: bit `i` is switch `i`, bit 0 the most
    /// proximal on the segment's link.
    pub touch_bits: &'a [Option<u8>],
}

/// A wall estimate, in the carriage frame's terms: origin at the base pivot, `x` along the
/// stage's travel, `y` toward the wall (the left of `x` when [`Self::wall_on_left`], else the
/// right). The wall is the line `y = distance_m + (x - preview_m) tan(wall_angle_rad)`.
///
/// (The angle's field is `wall_angle_rad` rather than `angle_rad`: a struct with both
/// `distance_m` and `angle_rad` reads as a scene's wall description, which only
/// `antenna-scene` holds.)
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatedWall {
    /// The wall's distance from the travel at `x = preview_m`, m.
    pub distance_m: f64,
    /// The wall's angle to the travel, rad (positive: the wall recedes as `x` grows); `None`
    /// for an estimator that gives none (`bend`), drawn parallel to the travel.
    pub wall_angle_rad: Option<f64>,
    /// Where along the travel the distance is estimated, m from the base pivot.
    pub preview_m: f64,
    /// The wall is on the left of the travel (`y` = the carriage frame's `+y`).
    pub wall_on_left: bool,
}

impl EstimatedWall {
    /// The point of the wall at `x_m` along the travel, in the carriage frame (`y` signed:
    /// `+y` is the left of the travel).
    pub fn point_at(&self, x_m: f64) -> [f64; 2] {
        let toward_wall =
            self.distance_m + (x_m - self.preview_m) * self.wall_angle_rad.unwrap_or(0.0).tan();
        let side = if self.wall_on_left { 1.0 } else { -1.0 };
        [x_m, side * toward_wall]
    }
}
