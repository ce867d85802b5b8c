//! The slope command-line programs. Each binary in `src/bin/` is a thin
//! `main` (parse, set up logging, call `run`); the logic lives in one module
//! per program here, so that it can be read and tested without a process.

pub mod capture;
pub mod capture_notify;
pub mod cli;
pub mod config_file;
pub mod convert;
pub mod demo;
pub mod echo;
pub mod estimator;
pub mod eval;
pub mod eval_artifacts;
pub mod export_format;
pub mod flag_rules;
pub mod health;
pub mod mcap_export;
pub mod mount_args;
pub mod mount_transform;
pub mod overlay;
pub mod overlay_marks;
pub mod plot;
pub mod ply;
pub mod record;
pub mod rejected_clouds;
pub mod render;
pub mod replay;
pub mod ros2_messages;
pub mod ros2_names;
pub mod rosbag2_export;
pub mod service_manager;
pub mod surfaces_json;
pub mod text;
pub mod unfinished_files;
