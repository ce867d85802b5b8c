//! `slope-import BAG --list`: the bag's topics with their types and
//! message counts, and which ones an import would read.

use std::io::Write;
use std::path::Path;

use anyhow::Context;

use crate::args::ImportArgs;
use crate::bag::TopicInfo;
use crate::topics::choose;

/// Prints the topics of `bag` on stdout; the choice an import would make,
/// or why it could not, under them.
pub fn print(bag: &Path, topics: &[TopicInfo], args: &ImportArgs) -> anyhow::Result<()> {
    let chosen = choose(topics, &args.wanted());
    let width = topics
        .iter()
        .map(|t| t.name.len())
        .max()
        .unwrap_or(5)
        .max(5);
    let type_width = topics
        .iter()
        .map(|t| t.message_type.len())
        .max()
        .unwrap_or(4)
        .max(4);
    let mut text = format!("{bag}: {} topics\n", topics.len(), bag = bag.display());
    text.push_str(&format!(
        "{:<width$}  {:<type_width$}  {:>8}\n",
        "topic", "type", "messages"
    ));
    for topic in topics {
        let count = topic
            .count
            .map_or_else(|| "?".to_string(), |c| c.to_string());
        let role = match &chosen {
            Ok(c) if c.depth == topic.name => "  <- depth",
            Ok(c) if c.info == topic.name => "  <- camera info",
            Ok(c) if c.color.as_deref() == Some(topic.name.as_str()) => "  <- colour",
            Ok(c) if c.tf_static.as_deref() == Some(topic.name.as_str()) => "  <- mount",
            _ => "",
        };
        text.push_str(&format!(
            "{:<width$}  {:<type_width$}  {count:>8}{role}\n",
            topic.name, topic.message_type
        ));
    }
    if let Err(why) = &chosen {
        text.push_str(&format!("an import would fail: {why}\n"));
    }
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
        .context("cannot write to stdout")
}
