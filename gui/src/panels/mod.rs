//! The panels, one per file, each a struct with `ui(&mut self, ui, ...)` taking the data it
//! draws (egui_demo_lib style).

pub mod chain;
pub mod controls;
pub mod estimate;
pub mod follow_error;
pub mod follow_info;
pub mod health;
pub mod joint_angles;
pub mod stage;
pub mod timeline;
pub mod touch_raster;

pub use chain::ChainPanel;
pub use controls::ControlsPanel;
pub use estimate::EstimatePanel;
pub use follow_error::FollowErrorPanel;
pub use follow_info::FollowInfoPanel;
pub use health::HealthPanel;
pub use joint_angles::JointAnglesPanel;
pub use stage::{StageInfo, StagePanel};
pub use timeline::{TimelineAction, TimelinePanel};
pub use touch_raster::TouchRasterPanel;
