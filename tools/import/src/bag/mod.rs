//! Reading ROS bags, whatever their format, as one stream of messages
//! ([`Bag::read`]) and a list of topics ([`Bag::topics`]).
//!
//! | file | format | crate |
//! |---|---|---|
//! | `ros1.rs` | ROS 1 `.bag` (version 2.0) | `rosbag` |
//! | `mcap_file.rs` | ROS 2 MCAP storage (`.mcap`) | `mcap` |
//! | `sqlite.rs` | ROS 2 SQLite storage (`.db3`) | `rusqlite` |
//! | `rosbag2_dir.rs` | a ROS 2 bag directory (`metadata.yaml`) | `serde_yaml` |
//!
//! Messages stay serialised here ([`Serialization`] says how);
//! `crate::messages` decodes those the import needs.

mod mcap_file;
mod ros1;
mod rosbag2_dir;
mod sqlite;

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

/// Why a bag cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path} is not a ROS bag: {reason}")]
    NotABag { path: PathBuf, reason: String },
    #[error("{path}: {reason}")]
    Unsupported { path: PathBuf, reason: String },
    #[error("{path} is damaged or truncated: {reason}")]
    Damaged { path: PathBuf, reason: String },
}

/// How a bag's messages are serialised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Serialization {
    /// ROS 1 (little-endian, packed, no alignment).
    Ros1,
    /// ROS 2: CDR with its encapsulation header.
    Cdr,
}

/// A topic of a bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicInfo {
    pub name: String,
    /// The message type as the bag names it (`sensor_msgs/Image` in ROS 1,
    /// `sensor_msgs/msg/Image` in ROS 2).
    pub message_type: String,
    /// Messages on the topic, when the bag's index says.
    pub count: Option<u64>,
}

impl TopicInfo {
    /// The type without ROS 2's `/msg/` (`sensor_msgs/Image`), to compare
    /// across ROS versions.
    pub fn plain_type(&self) -> String {
        plain_type(&self.message_type)
    }
}

/// A type name without ROS 2's `/msg/`.
pub fn plain_type(name: &str) -> String {
    name.replacen("/msg/", "/", 1)
}

/// One message, still serialised.
#[derive(Debug, Clone, Copy)]
pub struct BagMessage<'a> {
    pub topic: &'a str,
    /// When the recorder received it, ns since the Unix epoch.
    pub log_time_ns: u64,
    pub data: &'a [u8],
}

/// How far [`Bag::read`] got when the bag ended early.
#[derive(Debug)]
pub struct Truncated {
    /// Messages delivered before the damage.
    pub messages: u64,
    /// The log time of the last message delivered, ns.
    pub last_log_time_ns: Option<u64>,
    pub error: BagError,
}

/// An open bag of any format.
pub enum Bag {
    Ros1(ros1::Ros1Bag),
    Mcap(mcap_file::McapBag),
    Sqlite(sqlite::SqliteBag),
    /// A ROS 2 bag directory: its storage files in order.
    Split(Vec<Bag>),
}

impl Bag {
    /// Opens `path`: a ROS 1 `.bag`, a ROS 2 bag directory, or one `.mcap`
    /// or `.db3` file of a ROS 2 bag.
    pub fn open(path: &Path) -> Result<Self, BagError> {
        if path.is_dir() {
            let files = rosbag2_dir::storage_files(path)?;
            return match files.len() {
                1 => Self::open_file(&files[0]),
                _ => files
                    .iter()
                    .map(|f| Self::open_file(f))
                    .collect::<Result<_, _>>()
                    .map(Self::Split),
            };
        }
        Self::open_file(path)
    }

    fn open_file(path: &Path) -> Result<Self, BagError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("bag") => ros1::Ros1Bag::open(path).map(Self::Ros1),
            Some("mcap") => mcap_file::McapBag::open(path).map(Self::Mcap),
            Some("db3") => sqlite::SqliteBag::open(path).map(Self::Sqlite),
            _ => Err(BagError::NotABag {
                path: path.to_path_buf(),
                reason: "expected a ROS 1 .bag, a ROS 2 bag directory (with metadata.yaml), or \
                         a ROS 2 .mcap or .db3 file"
                    .to_string(),
            }),
        }
    }

    /// How the messages are serialised.
    pub fn serialization(&self) -> Serialization {
        match self {
            Self::Ros1(_) => Serialization::Ros1,
            _ => Serialization::Cdr,
        }
    }

    /// The topics, with their types and (when indexed) message counts.
    pub fn topics(&self) -> Result<Vec<TopicInfo>, BagError> {
        match self {
            Self::Ros1(bag) => bag.topics(),
            Self::Mcap(bag) => bag.topics(),
            Self::Sqlite(bag) => bag.topics(),
            Self::Split(bags) => {
                let mut merged: Vec<TopicInfo> = Vec::new();
                for bag in bags {
                    for topic in bag.topics()? {
                        match merged.iter_mut().find(|t| t.name == topic.name) {
                            Some(known) => {
                                known.count = known.count.zip(topic.count).map(|(a, b)| a + b);
                            }
                            None => merged.push(topic),
                        }
                    }
                }
                Ok(merged)
            }
        }
    }

    /// Calls `on_message` with every message, in the bag's order, until it
    /// breaks. `Err` only when the bag could not be read at all; a bag
    /// damaged after its start gives `Ok(Some(Truncated))` after the
    /// messages before the damage.
    pub fn read(
        &self,
        on_message: &mut dyn FnMut(BagMessage<'_>) -> ControlFlow<()>,
    ) -> Result<Option<Truncated>, BagError> {
        let mut counted = Counted {
            messages: 0,
            last_log_time_ns: None,
            stopped: false,
            on_message,
        };
        let result = self.read_counted(&mut counted);
        result.map(|end| {
            end.map(|error| Truncated {
                messages: counted.messages,
                last_log_time_ns: counted.last_log_time_ns,
                error,
            })
        })
    }

    fn read_counted(&self, counted: &mut Counted<'_>) -> Result<Option<BagError>, BagError> {
        match self {
            Self::Ros1(bag) => bag.read(&mut |m| counted.deliver(m)),
            Self::Mcap(bag) => bag.read(&mut |m| counted.deliver(m)),
            Self::Sqlite(bag) => bag.read(&mut |m| counted.deliver(m)),
            Self::Split(bags) => {
                for bag in bags {
                    if let Some(damage) = bag.read_counted(counted)? {
                        return Ok(Some(damage));
                    }
                    if counted.stopped {
                        break;
                    }
                }
                Ok(None)
            }
        }
    }
}

/// Counts what was delivered, for [`Truncated`].
struct Counted<'a> {
    messages: u64,
    last_log_time_ns: Option<u64>,
    /// Set once `on_message` broke: the next files of a split bag are not read.
    stopped: bool,
    on_message: &'a mut dyn FnMut(BagMessage<'_>) -> ControlFlow<()>,
}

impl Counted<'_> {
    fn deliver(&mut self, message: BagMessage<'_>) -> ControlFlow<()> {
        self.messages += 1;
        self.last_log_time_ns = Some(message.log_time_ns);
        let flow = (self.on_message)(message);
        self.stopped |= flow.is_break();
        flow
    }
}
