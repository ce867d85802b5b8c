//! ROS 1 bags (format 2.0), read with the `rosbag` crate: the connections
//! and message counts from the index section, the messages chunk by chunk.
//!
//! `rosbag` 0.6 slices the file at the header's `index_pos` without a
//! check, so a bag cut short (`index_pos` beyond the end) or never closed
//! (`index_pos` 0, a `.bag.active`) would panic in it. [`index_pos`] reads
//! that one field first (the bag header record: the version line, then a
//! length-prefixed list of `name=value` fields) and such a bag is read from
//! a copy whose `index_pos` is the end of the file: every complete chunk,
//! then the point where the data stops.

use std::collections::HashMap;
use std::io::{Read, Write};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use rosbag::{ChunkRecord, IndexRecord, MessageRecord, RosBag};

use super::{BagError, BagMessage, TopicInfo};

const VERSION_LINE: &[u8] = b"#ROSBAG V2.0\n";

pub struct Ros1Bag {
    path: PathBuf,
    bag: RosBag,
    /// True when `bag` is a copy with its index position set to the end of
    /// the file (the original was truncated or not closed).
    unindexed: bool,
    /// Keeps the copy while `bag` maps it.
    _copy: Option<tempfile::NamedTempFile>,
}

/// Where `index_pos` (8 bytes, little-endian) sits in the file and its
/// value, read from the bag header record.
fn index_pos(path: &Path) -> Result<(usize, u64), BagError> {
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let not_a_bag = |reason: &str| BagError::NotABag {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut start = [0u8; VERSION_LINE.len() + 4];
    file.read_exact(&mut start)
        .map_err(|_| not_a_bag("shorter than a bag header"))?;
    if &start[..VERSION_LINE.len()] != VERSION_LINE {
        return Err(not_a_bag(
            "no '#ROSBAG V2.0' line (a ROS 1 bag of version 2.0 was expected)",
        ));
    }
    let mut len_bytes = [0u8; 4];
    len_bytes.copy_from_slice(&start[VERSION_LINE.len()..]);
    let header_len = u32::from_le_bytes(len_bytes) as usize;
    if header_len > 1 << 16 {
        return Err(not_a_bag("its header record is implausibly long"));
    }
    let mut header = vec![0u8; header_len];
    file.read_exact(&mut header)
        .map_err(|_| not_a_bag("its header record is cut short"))?;
    let mut at = 0;
    while at + 4 <= header.len() {
        let mut len_bytes = [0u8; 4];
        len_bytes.copy_from_slice(&header[at..at + 4]);
        let len = u32::from_le_bytes(len_bytes) as usize;
        let field = header
            .get(at + 4..at + 4 + len)
            .ok_or_else(|| not_a_bag("its header record is malformed"))?;
        if let Some(value) = field.strip_prefix(b"index_pos=") {
            let bytes: [u8; 8] = value
                .try_into()
                .map_err(|_| not_a_bag("its index_pos is not 8 bytes"))?;
            let offset = VERSION_LINE.len() + 4 + at + 4 + b"index_pos=".len();
            return Ok((offset, u64::from_le_bytes(bytes)));
        }
        at += 4 + len;
    }
    Err(not_a_bag("its header has no index_pos"))
}

/// A copy of the bag at `path` whose `index_pos` (at `offset`) is the end
/// of the file.
fn copy_with_index_at_end(path: &Path, offset: usize) -> Result<tempfile::NamedTempFile, BagError> {
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut data = std::fs::read(path).map_err(io)?;
    let end = (data.len() as u64).to_le_bytes();
    data[offset..offset + 8].copy_from_slice(&end);
    let mut copy = tempfile::NamedTempFile::new().map_err(io)?;
    copy.write_all(&data).map_err(io)?;
    copy.flush().map_err(io)?;
    Ok(copy)
}

impl Ros1Bag {
    pub fn open(path: &Path) -> Result<Self, BagError> {
        let (offset, index) = index_pos(path)?;
        let len = std::fs::metadata(path)
            .map_err(|source| BagError::Io {
                path: path.to_path_buf(),
                source,
            })?
            .len();
        let unindexed = index == 0 || index > len || (offset + 8) as u64 > len;
        let copy = if unindexed {
            tracing::warn!(
                "{} has no index (cut short, or still being recorded): reading its chunks from a \
                 copy, up to where the data stops",
                path.display()
            );
            Some(copy_with_index_at_end(path, offset)?)
        } else {
            None
        };
        let open_path = copy.as_ref().map_or(path, |c| c.path());
        let bag = RosBag::new(open_path).map_err(|e| BagError::NotABag {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            bag,
            unindexed,
            _copy: copy,
        })
    }

    fn damaged(&self, reason: impl std::fmt::Display) -> BagError {
        BagError::Damaged {
            path: self.path.clone(),
            reason: reason.to_string(),
        }
    }

    /// Connections and counts from the index section; for a bag without
    /// one, the connections found in its chunks (counts unknown).
    pub fn topics(&self) -> Result<Vec<TopicInfo>, BagError> {
        let mut topics: Vec<(u32, TopicInfo)> = Vec::new();
        let mut counts: HashMap<u32, u64> = HashMap::new();
        if self.unindexed {
            let _ = self.read_chunks(&mut |_| ControlFlow::Continue(()), &mut |id, topic, ty| {
                topics.push((id, topic_info(topic, ty)));
            });
            topics.dedup_by_key(|(id, _)| *id);
            return Ok(merge_by_topic(topics, None));
        }
        for record in self.bag.index_records() {
            match record.map_err(|e| self.damaged(e))? {
                IndexRecord::Connection(c) => topics.push((c.id, topic_info(c.topic, c.tp))),
                IndexRecord::ChunkInfo(info) => {
                    for entry in info.entries() {
                        *counts.entry(entry.conn_id).or_default() += u64::from(entry.count);
                    }
                }
                IndexRecord::IndexData(_) => {}
            }
        }
        Ok(merge_by_topic(topics, Some(&counts)))
    }

    /// Every message in the chunks' order; `Ok(Some(error))` when the
    /// chunks stop early.
    pub fn read(
        &self,
        on_message: &mut dyn FnMut(BagMessage<'_>) -> ControlFlow<()>,
    ) -> Result<Option<BagError>, BagError> {
        self.read_chunks(on_message, &mut |_, _, _| {})
    }

    fn read_chunks(
        &self,
        on_message: &mut dyn FnMut(BagMessage<'_>) -> ControlFlow<()>,
        on_connection: &mut dyn FnMut(u32, &str, &str),
    ) -> Result<Option<BagError>, BagError> {
        let mut topics: HashMap<u32, String> = HashMap::new();
        for record in self.bag.chunk_records() {
            let chunk = match record {
                Ok(ChunkRecord::Chunk(chunk)) => chunk,
                Ok(ChunkRecord::IndexData(_)) => continue,
                Err(e) => return Ok(Some(self.damaged(format!("a chunk cannot be read ({e})")))),
            };
            for message in chunk.messages() {
                match message {
                    Ok(MessageRecord::Connection(c)) => {
                        on_connection(c.id, c.topic, c.tp);
                        topics.insert(c.id, c.topic.to_string());
                    }
                    Ok(MessageRecord::MessageData(m)) => {
                        let Some(topic) = topics.get(&m.conn_id) else {
                            return Ok(Some(self.damaged(format!(
                                "a message of connection {} comes before the connection",
                                m.conn_id
                            ))));
                        };
                        let message = BagMessage {
                            topic,
                            log_time_ns: m.time,
                            data: m.data,
                        };
                        if on_message(message).is_break() {
                            return Ok(None);
                        }
                    }
                    Err(e) => {
                        return Ok(Some(
                            self.damaged(format!("a chunk's messages cannot be read ({e})")),
                        ))
                    }
                }
            }
        }
        Ok(None)
    }
}

fn topic_info(topic: &str, message_type: &str) -> TopicInfo {
    TopicInfo {
        name: topic.to_string(),
        message_type: message_type.to_string(),
        count: None,
    }
}

/// One entry per topic (a topic may have several connections), with the
/// sum of its connections' counts when `counts` is given.
fn merge_by_topic(
    connections: Vec<(u32, TopicInfo)>,
    counts: Option<&HashMap<u32, u64>>,
) -> Vec<TopicInfo> {
    let mut topics: Vec<TopicInfo> = Vec::new();
    for (id, mut topic) in connections {
        let count = counts.map(|c| c.get(&id).copied().unwrap_or(0));
        match topics.iter_mut().find(|t| t.name == topic.name) {
            Some(known) => known.count = known.count.zip(count).map(|(a, b)| a + b),
            None => {
                topic.count = count;
                topics.push(topic);
            }
        }
    }
    topics
}
