//! `slope-import BAG -o RECORDING`: a ROS 1 or ROS 2 bag of a depth camera
//! as a recording (the recording format), so that `slope-eval`,
//! `slope-replay` and `slope-convert` take a robot's own bags.
//!
//! | file | holds |
//! |---|---|
//! | `args.rs` | the command line ([`ImportArgs`]) |
//! | `bag/` | reading ROS 1 bags and ROS 2 MCAP and SQLite storage as one stream of messages |
//! | `messages.rs` | decoding the messages read (CDR, ROS 1) |
//! | `topics.rs` | which topics are the depth images, the camera info, `/tf_static` |
//! | `depth.rs` | depth images as millimetres (16UC1, 32FC1, compressedDepth) |
//! | `color.rs` | the registered colour images, matched by stamp |
//! | `mount.rs` | the mount from `/tf_static` |
//! | `import.rs` | the import's one pass over the bag |
//! | `list.rs` | `--list` |

mod args;
pub mod bag;
pub mod color;
pub mod depth;
mod import;
mod list;
pub mod messages;
pub mod mount;
pub mod topics;

use std::io::IsTerminal;
use std::path::Path;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use slope_sensor::publish::StopFlag;

pub use args::ImportArgs;
pub use import::{ImportStats, Importer};

use bag::Bag;

/// Runs `slope-import` (or `--list`).
pub fn run(args: &ImportArgs, stop: &StopFlag) -> anyhow::Result<()> {
    let bag = Bag::open(&args.bag)?;
    let topics = bag.topics()?;
    if args.list {
        return list::print(&args.bag, &topics, args);
    }
    let Some(out) = args.output.as_deref() else {
        anyhow::bail!("an output directory is required: give it as -o DIR");
    };
    let existed = check_output(out)?;
    let chosen = topics::choose(&topics, &args.wanted())?;
    tracing::info!(
        depth = chosen.depth,
        info = chosen.info,
        color = chosen.color.as_deref().unwrap_or("-"),
        tf_static = chosen.tf_static.as_deref().unwrap_or("-"),
        "importing {}",
        args.bag.display()
    );
    let total = topics
        .iter()
        .find(|t| t.name == chosen.depth)
        .and_then(|t| t.count);
    let progress = progress_bar(args.log.quiet, total);
    let mut importer = Importer::new(args, &chosen, bag.serialization(), out, progress);
    let truncated = bag.read(&mut |message| importer.on_message(message, stop))?;
    match importer.finish(truncated) {
        Ok(stats) => {
            if stats.interrupted {
                tracing::warn!(
                    "interrupted; {} holds the {} frames imported",
                    out.display(),
                    stats.written
                );
            }
            tracing::info!(
                frames = stats.written,
                depth_images = stats.depth_messages,
                with_color = stats.with_color,
                skipped = stats.skipped,
                out = %out.display(),
                "imported"
            );
            Ok(())
        }
        Err(err) => {
            remove_if_empty(out, existed);
            Err(err)
        }
    }
}

/// Checks that `out` is new or an empty directory (before the bag is
/// read); whether it existed.
fn check_output(out: &Path) -> anyhow::Result<bool> {
    if !out.exists() {
        return Ok(false);
    }
    let empty = out.is_dir()
        && std::fs::read_dir(out)
            .with_context(|| format!("cannot read {}", out.display()))?
            .next()
            .is_none();
    if !empty {
        anyhow::bail!(
            "{} exists and is not an empty directory; give a new name",
            out.display()
        );
    }
    Ok(true)
}

/// After a failed import: removes a recording without frames (and the
/// directory, if the import made it).
fn remove_if_empty(out: &Path, existed: bool) {
    let frames = std::fs::read_dir(out.join("depth"))
        .map(|d| d.count())
        .unwrap_or(0);
    if frames > 0 || !out.exists() {
        return;
    }
    let removed = if existed {
        ["recording.toml", "frames.csv"]
            .iter()
            .map(|f| out.join(f))
            .filter(|p| p.exists())
            .try_for_each(std::fs::remove_file)
            .and_then(|()| std::fs::remove_dir(out.join("depth")).or(Ok(())))
    } else {
        std::fs::remove_dir_all(out)
    };
    if let Err(err) = removed {
        tracing::debug!("cannot remove the empty recording {}: {err}", out.display());
    }
}

/// A bar over the depth topic's messages on stderr (a spinner when the bag
/// does not count them); hidden with `-q` or when stderr is not a terminal.
fn progress_bar(quiet: bool, total: Option<u64>) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(total, ProgressDrawTarget::stderr());
    let template = match total {
        Some(_) => "[{bar:30}] {pos}/{len} depth images, {eta} left",
        None => "{spinner} {pos} depth images",
    };
    // The templates are constants; should one fail to parse, the default
    // style still works.
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
