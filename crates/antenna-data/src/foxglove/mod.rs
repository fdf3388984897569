//! The antenna in Foxglove's standard schemas: the chain's frames
//! (`foxglove.FrameTransforms`) and a 3D scene of its links, touch switches, walls and
//! estimated wall (`foxglove.SceneUpdate`), protobuf-encoded by the `foxglove` crate (no
//! server, no async runtime). The recordings carry them ([`crate::record`]); antennad's live
//! Foxglove server sends the same messages.
//!
//! # Frames
//!
//! Every frame is right-handed with `z` up, out of the plane the antenna moves in; angles are
//! counter-clockwise about `z`.
//!
//! | frame | parent | origin | rotation |
//! |---|---|---|---|
//! | `world` | (root) | the scene's origin (the simulator's ground frame) | |
//! | `carriage` | `world` | [`ChainModel::origin_m`] + `stage_m` along the travel: the base pivot | [`ChainModel::travel_angle_rad`]: `x` along the stage's travel |
//! | `link_0` | `carriage` | the base pivot | [`ChainModel::base_mount_angle_rad`] + `servo_rad`: `x` along the base link |
//! | `link_k` (`k >= 1`) | `link_{k-1}` | `link_{k-1}`'s length along its `x` (joint `k`) | segment `k - 1`'s joint angle |
//!
//! So link `k` lies from `(0, 0, 0)` to `(L_k, 0, 0)` in its own frame, and with
//! `phi_k = travel + mount + servo + theta_1 + ... + theta_k` the tip of the chain is at
//! `origin + stage (cos travel, sin travel) + sum_k L_k (cos phi_k, sin phi_k)` in `world`.
//! Segment `k - 1`'s touch switches are on link `k` (the base link has none), switch `j`
//! drawn at `(j + 1/2)/4` of its length. An estimated wall ([`EstimatedWall`]) is drawn in
//! `carriage`, whose `x` is the estimate's and whose `+y` is its "toward the wall" when the
//! wall is on the left (its `-y` otherwise).
//!
//! # Missing readings
//!
//! A reading that is missing ([`ChainPose`]'s `None`: a failed read of a segment, a stage or
//! servo not reporting) leaves out the one transform it places (`carriage`, `link_0`, or the
//! joint's link), and only that one: Foxglove then keeps the last transform it had for that
//! frame (the last good read), and the frames beyond it still move with their own joints. A
//! missing touch word draws its switches faintly ([`SWITCH_UNKNOWN_COLOR`]).
//!
//! # Example
//!
//! ```
//! use antenna_data::foxglove::{ChainModel, ChainPose, ChannelSchema, encode, frame_transforms};
//! use foxglove::messages::FrameTransforms;
//!
//! let model = ChainModel { link_lengths_m: vec![0.04; 3], ..ChainModel::default() };
//! let pose = ChainPose {
//!     t_ns: 1_000_000_000,
//!     stage_m: Some(0.01),
//!     servo_rad: Some(0.0),
//!     joint_angles_rad: &[Some(0.1), Some(-0.05)],
//!     touch_bits: &[Some(0b0001), None],
//! };
//! let transforms = frame_transforms(&model, &pose);
//! assert_eq!(transforms.transforms.len(), 4); // carriage, link_0, link_1, link_2
//! let schema = ChannelSchema::of::<FrameTransforms>()?;
//! assert_eq!((schema.name.as_str(), schema.encoding.as_str()), ("foxglove.FrameTransforms", "protobuf"));
//! assert!(!encode(&transforms)?.is_empty());
//! # Ok::<(), antenna_data::foxglove::EncodeError>(())
//! ```

mod encode;
mod model;
mod scene;
#[cfg(test)]
mod tests;
mod transforms;

pub use encode::{ChannelSchema, EncodeError, encode, encode_into};
pub use model::{ChainModel, ChainPose, EstimatedWall};
pub use scene::{
    ESTIMATED_WALL_COLOR, ESTIMATED_WALL_ID, ESTIMATED_WALL_LENGTH_M, LINK_COLOR,
    SWITCH_CLOSED_COLOR, SWITCH_OPEN_COLOR, SWITCH_UNKNOWN_COLOR, SWITCHES_PER_LINK, WALL_COLOR,
    chain_scene_update, link_entity_id, scene_update, switch_color, wall_entity_id,
    walls_scene_update,
};
pub use transforms::{CARRIAGE_FRAME, WORLD_FRAME, frame_transforms, link_frame_id, timestamp};
