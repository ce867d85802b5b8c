//! ROS 2 bags in MCAP storage, read with the `mcap` crate: the topics and
//! counts from the file's summary, the messages in file order with
//! [`mcap::MessageStream`] (which reports a file cut short after the last
//! message it could read). Only `cdr`-encoded channels are ROS 2
//! messages; others (Foxglove's JSON) are listed but refused as depth.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use super::{BagError, BagMessage, TopicInfo};

pub struct McapBag {
    path: PathBuf,
    map: memmap2::Mmap,
}

impl McapBag {
    pub fn open(path: &Path) -> Result<Self, BagError> {
        let io = |source| BagError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        // SAFETY: the map is read only and lives as long as `self`; the
        // file is opened read-only. Another process truncating the file
        // meanwhile would make a read fault (SIGBUS), as for every reader
        // that maps its input (the `mcap` crate's own examples do).
        let map = unsafe { memmap2::Mmap::map(&file) }.map_err(io)?;
        if !map.starts_with(mcap::MAGIC) {
            return Err(BagError::NotABag {
                path: path.to_path_buf(),
                reason: "no MCAP magic at its start".to_string(),
            });
        }
        Ok(Self {
            path: path.to_path_buf(),
            map,
        })
    }

    fn damaged(&self, reason: impl std::fmt::Display) -> BagError {
        BagError::Damaged {
            path: self.path.clone(),
            reason: reason.to_string(),
        }
    }

    /// From the summary; a file without one (cut short) is scanned.
    pub fn topics(&self) -> Result<Vec<TopicInfo>, BagError> {
        let summary = mcap::Summary::read(&self.map).ok().flatten();
        let Some(summary) = summary else {
            return self.scan_topics();
        };
        let counts = summary.stats.map(|s| s.channel_message_counts);
        let mut channels: Vec<_> = summary.channels.values().collect();
        channels.sort_by_key(|c| c.id);
        let mut topics: Vec<TopicInfo> = Vec::new();
        for channel in channels {
            let count = counts
                .as_ref()
                .map(|c| c.get(&channel.id).copied().unwrap_or(0));
            let message_type = channel
                .schema
                .as_ref()
                .map_or(String::new(), |s| s.name.clone());
            match topics.iter_mut().find(|t| t.name == channel.topic) {
                Some(known) => known.count = known.count.zip(count).map(|(a, b)| a + b),
                None => topics.push(TopicInfo {
                    name: channel.topic.clone(),
                    message_type,
                    count,
                }),
            }
        }
        Ok(topics)
    }

    /// Topics and counts by reading every message (a file without a
    /// summary).
    fn scan_topics(&self) -> Result<Vec<TopicInfo>, BagError> {
        let mut topics: Vec<TopicInfo> = Vec::new();
        let stream = mcap::MessageStream::new(&self.map).map_err(|e| self.damaged(e))?;
        for message in stream {
            let Ok(message) = message else { break };
            let channel = &message.channel;
            match topics.iter_mut().find(|t| t.name == channel.topic) {
                Some(known) => known.count = known.count.map(|c| c + 1),
                None => topics.push(TopicInfo {
                    name: channel.topic.clone(),
                    message_type: channel
                        .schema
                        .as_ref()
                        .map_or(String::new(), |s| s.name.clone()),
                    count: Some(1),
                }),
            }
        }
        Ok(topics)
    }

    pub fn read(
        &self,
        on_message: &mut dyn FnMut(BagMessage<'_>) -> ControlFlow<()>,
    ) -> Result<Option<BagError>, BagError> {
        let stream = mcap::MessageStream::new(&self.map).map_err(|e| self.damaged(e))?;
        for message in stream {
            let message = match message {
                Ok(message) => message,
                Err(e) => return Ok(Some(self.damaged(e))),
            };
            if message.channel.message_encoding != "cdr" {
                continue;
            }
            let flow = on_message(BagMessage {
                topic: &message.channel.topic,
                log_time_ns: message.log_time,
                data: &message.data,
            });
            if flow.is_break() {
                break;
            }
        }
        Ok(None)
    }
}
