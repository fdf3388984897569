//! [`Channels`]: the server's channels and what the hub's stream messages become on them.

use super::error::FoxgloveError;
use super::schemas::{
    ESTIMATE_SCHEMA, ESTIMATE_TOPIC, SAMPLES_SCHEMA, SAMPLES_TOPIC, SCENE_TOPIC, STATUS_SCHEMA,
    STATUS_TOPIC, TRANSFORMS_TOPIC, estimate_schema, samples_schema, status_schema,
};
use antenna_data::foxglove::{
    ChainModel, ChainPose, ESTIMATED_WALL_ID, EstimatedWall, chain_scene_update, frame_transforms,
    scene_update,
};
use antenna_data::stream::{EstimateMessage, StreamMessage};
use foxglove::messages::{FrameTransforms, SceneUpdate};
use foxglove::{Channel, Context, PartialMetadata, RawChannel, Schema};
use serde_json::Value;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// How often the whole scene (the walls too) is sent again, besides to every new subscriber
/// of the scene, ns.
const SCENE_REFRESH_NS: u64 = 2_000_000_000;

/// The chain as the newest samples gave it.
#[derive(Debug, Default)]
struct Pose {
    t_ns: u64,
    stage_m: Option<f64>,
    servo_rad: Option<f64>,
    joint_angles_rad: Vec<Option<f64>>,
    touch_bits: Vec<Option<u8>>,
}

/// What [`Channels::publish`] needs besides the channels.
#[derive(Debug, Clone)]
pub(super) struct ChannelSettings {
    /// The chain drawn.
    pub model: ChainModel,
    /// Unix-epoch nanoseconds of the daemon's clock origin: every message's log time and
    /// time stamp is this plus its `t_ns`.
    pub unix_origin_ns: u64,
    /// The 3D channels' period, ns (`[foxglove] scene_hz`).
    pub scene_period_ns: u64,
    /// The estimated wall is on the left of the travel (`[estimate] wall_side`).
    pub wall_on_left: bool,
}

/// The server's channels, in their own context (never the SDK's default one).
pub(super) struct Channels {
    settings: ChannelSettings,
    samples: Arc<RawChannel>,
    status: Arc<RawChannel>,
    estimate: Arc<RawChannel>,
    transforms: Channel<FrameTransforms>,
    scene: Channel<SceneUpdate>,
    /// Set when a client subscribes to the scene: the whole scene goes out with the next
    /// update.
    walls_due: Arc<AtomicBool>,
    /// When the whole scene was last sent (Unix-epoch ns).
    scene_refreshed_ns: Option<u64>,
    /// The touch words and the estimated wall the last scene update drew: the links are drawn
    /// in their own frames (the transforms move them), so the scene changes only with these.
    scene_touch_bits: Vec<Option<u8>>,
    scene_estimate: Option<EstimatedWall>,
    next_scene_ns: u64,
    pose: Pose,
    estimated_wall: Option<EstimatedWall>,
}

impl std::fmt::Debug for Channels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Channels")
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

fn json_channel(
    context: &Arc<Context>,
    topic: &str,
    schema_name: &str,
    schema: &Value,
) -> Result<Arc<RawChannel>, FoxgloveError> {
    context
        .channel_builder(topic)
        .message_encoding("json")
        .schema(Schema::new(
            schema_name,
            "jsonschema",
            schema.to_string().into_bytes(),
        ))
        .build_raw()
        .map_err(|e| FoxgloveError::Channel {
            topic: topic.to_owned(),
            reason: e.to_string(),
        })
}

impl Channels {
    /// The channels in `context`; `walls_due` is set by the server when a client subscribes
    /// to the scene.
    pub(super) fn new(
        context: &Arc<Context>,
        settings: ChannelSettings,
        walls_due: Arc<AtomicBool>,
    ) -> Result<Self, FoxgloveError> {
        Ok(Self {
            samples: json_channel(context, SAMPLES_TOPIC, SAMPLES_SCHEMA, &samples_schema())?,
            status: json_channel(context, STATUS_TOPIC, STATUS_SCHEMA, &status_schema())?,
            estimate: json_channel(context, ESTIMATE_TOPIC, ESTIMATE_SCHEMA, &estimate_schema())?,
            transforms: context
                .channel_builder(TRANSFORMS_TOPIC)
                .build::<FrameTransforms>(),
            scene: context.channel_builder(SCENE_TOPIC).build::<SceneUpdate>(),
            walls_due,
            scene_refreshed_ns: None,
            scene_touch_bits: Vec::new(),
            scene_estimate: None,
            next_scene_ns: 0,
            pose: Pose::default(),
            estimated_wall: None,
            settings,
        })
    }

    /// The Unix-epoch time of `t_ns` on the daemon's clock.
    fn unix_ns(&self, t_ns: u64) -> u64 {
        self.settings.unix_origin_ns.saturating_add(t_ns)
    }

    /// `message`'s JSON line (without its newline) on `channel`, if anyone listens.
    fn log_json(&self, channel: &RawChannel, t_ns: u64, message: &StreamMessage) {
        if !channel.has_sinks() {
            return;
        }
        match serde_json::to_vec(message) {
            Ok(line) => {
                channel.log_with_meta(&line, PartialMetadata::with_log_time(self.unix_ns(t_ns)))
            }
            Err(e) => {
                tracing::warn!(target: "antennad", "foxglove: {} not encoded: {e}", channel.topic())
            }
        }
    }

    /// Takes one stream message: samples, status and estimate go out as they are on their
    /// channels; the newest samples (and estimate) make the 3D channels at their rate.
    pub(super) fn publish(&mut self, message: &StreamMessage) {
        match message {
            StreamMessage::Samples {
                t_ns,
                segments,
                stage_position_m,
                base_angle_deg,
                ..
            } => {
                self.log_json(&self.samples, *t_ns, message);
                let pose = &mut self.pose;
                pose.t_ns = *t_ns;
                pose.stage_m = *stage_position_m;
                pose.servo_rad = base_angle_deg.map(f64::to_radians);
                pose.joint_angles_rad.clear();
                pose.joint_angles_rad
                    .extend(segments.iter().map(|s| s.angle_rad));
                pose.touch_bits.clear();
                pose.touch_bits
                    .extend(segments.iter().map(|s| s.touch_bits));
                if *t_ns >= self.next_scene_ns {
                    self.next_scene_ns = t_ns.saturating_add(self.settings.scene_period_ns);
                    self.publish_scene();
                }
            }
            StreamMessage::Status { t_ns, .. } => self.log_json(&self.status, *t_ns, message),
            StreamMessage::Estimate(estimate) => {
                self.estimated_wall = estimated_wall(estimate, self.settings.wall_on_left);
                self.log_json(&self.estimate, estimate.t_ns, message);
            }
            _ => {}
        }
    }

    /// The transforms and the scene of the newest samples, to whoever listens.
    fn publish_scene(&mut self) {
        let unix_ns = self.unix_ns(self.pose.t_ns);
        let pose = ChainPose {
            t_ns: unix_ns,
            stage_m: self.pose.stage_m,
            servo_rad: self.pose.servo_rad,
            joint_angles_rad: &self.pose.joint_angles_rad,
            touch_bits: &self.pose.touch_bits,
        };
        let meta = PartialMetadata::with_log_time(unix_ns);
        if self.transforms.has_sinks() {
            self.transforms
                .log_with_meta(&frame_transforms(&self.settings.model, &pose), meta);
        }
        if self.scene.has_sinks() {
            // The whole scene to a new subscriber and every SCENE_REFRESH_NS; between, the
            // chain's entities (in the links' frames, moved by the transforms) only when a
            // touch switch changed, and the estimated wall alone when only it changed.
            let refresh = self.walls_due.swap(false, Ordering::Relaxed)
                || self
                    .scene_refreshed_ns
                    .is_none_or(|sent| unix_ns.saturating_sub(sent) >= SCENE_REFRESH_NS);
            let touched = self.scene_touch_bits != self.pose.touch_bits;
            let estimated = self.scene_estimate != self.estimated_wall;
            if refresh || touched || estimated {
                let model = &self.settings.model;
                let estimate = self.estimated_wall.as_ref();
                let update = if refresh {
                    self.scene_refreshed_ns = Some(unix_ns);
                    scene_update(model, &pose, estimate)
                } else {
                    let mut update = chain_scene_update(model, &pose, estimate);
                    if !touched {
                        update.entities.retain(|e| e.id == ESTIMATED_WALL_ID);
                    }
                    update
                };
                self.scene.log_with_meta(&update, meta);
                self.scene_touch_bits.clone_from(&self.pose.touch_bits);
                self.scene_estimate = self.estimated_wall;
            }
        }
    }

    /// Closes every channel (clients see them unadvertised).
    pub(super) fn close(&self) {
        self.samples.close();
        self.status.close();
        self.estimate.close();
        self.transforms.close();
        self.scene.close();
    }
}

/// The wall an estimate draws: `None` when it has no distance.
fn estimated_wall(estimate: &EstimateMessage, wall_on_left: bool) -> Option<EstimatedWall> {
    Some(EstimatedWall {
        distance_m: estimate.distance_m.filter(|d| d.is_finite())?,
        wall_angle_rad: estimate.angle_rad.filter(|a| a.is_finite()),
        preview_m: estimate.preview_m.filter(|p| p.is_finite()).unwrap_or(0.0),
        wall_on_left,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_estimate_without_a_distance_draws_no_wall() {
        let mut estimate = EstimateMessage {
            seq: 1,
            t_ns: 2,
            estimated_ns: 3,
            estimator: "bend".to_owned(),
            distance_m: Some(0.2),
            angle_rad: None,
            preview_m: Some(0.05),
            reason: None,
            true_distance_m: None,
            true_angle_rad: None,
        };
        assert_eq!(
            estimated_wall(&estimate, false),
            Some(EstimatedWall {
                distance_m: 0.2,
                wall_angle_rad: None,
                preview_m: 0.05,
                wall_on_left: false
            })
        );
        estimate.distance_m = None;
        assert_eq!(estimated_wall(&estimate, true), None);
    }
}
