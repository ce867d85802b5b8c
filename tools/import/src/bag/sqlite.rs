//! ROS 2 bags in SQLite storage (`.db3`), read with `rusqlite`: the
//! `topics` table (name, type, serialization format) and the `messages`
//! table (topic id, timestamp, data) in timestamp order. A damaged
//! database ("database disk image is malformed") ends the messages where
//! SQLite stops.

use std::collections::HashMap;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use rusqlite::{Connection, OpenFlags};

use super::{BagError, BagMessage, TopicInfo};

pub struct SqliteBag {
    path: PathBuf,
    db: Connection,
}

impl SqliteBag {
    pub fn open(path: &Path) -> Result<Self, BagError> {
        let db = Connection::open_with_flags(
            path,
            OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
        )
        .map_err(|e| BagError::NotABag {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        let bag = Self {
            path: path.to_path_buf(),
            db,
        };
        // A file that is no SQLite database fails here, at its first read;
        // so does a damaged one, whose tables may lie anywhere in the file.
        bag.topic_rows().map_err(|e| {
            let path = path.to_path_buf();
            if e.sqlite_error_code() == Some(rusqlite::ErrorCode::DatabaseCorrupt) {
                BagError::Damaged {
                    path,
                    reason: format!(
                        "{e}: SQLite cannot read its topics table, so no message can be found (a \
                         .db3 cut short loses the pages at its end; `sqlite3 BAG.db3 .recover` may \
                         save the rest)"
                    ),
                }
            } else {
                BagError::NotABag {
                    path,
                    reason: format!("no rosbag2 topics table ({e})"),
                }
            }
        })?;
        Ok(bag)
    }

    fn damaged(&self, reason: impl std::fmt::Display) -> BagError {
        BagError::Damaged {
            path: self.path.clone(),
            reason: reason.to_string(),
        }
    }

    /// `(id, name, type, serialization_format)` of every topic.
    fn topic_rows(&self) -> rusqlite::Result<Vec<(i64, String, String, String)>> {
        let mut statement = self
            .db
            .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")?;
        let rows = statement.query_map([], |row| {
            Ok((row.get(0)?, row.get(1)?, row.get(2)?, row.get(3)?))
        })?;
        rows.collect()
    }

    pub fn topics(&self) -> Result<Vec<TopicInfo>, BagError> {
        let rows = self.topic_rows().map_err(|e| self.damaged(e))?;
        let mut counts: HashMap<i64, u64> = HashMap::new();
        let counted: rusqlite::Result<()> = (|| {
            let mut statement = self
                .db
                .prepare("SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id")?;
            let rows = statement
                .query_map([], |row| Ok((row.get::<_, i64>(0)?, row.get::<_, i64>(1)?)))?;
            for row in rows {
                let (id, count) = row?;
                counts.insert(id, u64::try_from(count).unwrap_or(0));
            }
            Ok(())
        })();
        let known = counted.is_ok();
        Ok(rows
            .into_iter()
            .map(|(id, name, message_type, _)| TopicInfo {
                name,
                message_type,
                count: known.then(|| counts.get(&id).copied().unwrap_or(0)),
            })
            .collect())
    }

    pub fn read(
        &self,
        on_message: &mut dyn FnMut(BagMessage<'_>) -> ControlFlow<()>,
    ) -> Result<Option<BagError>, BagError> {
        let topics: HashMap<i64, (String, bool)> = self
            .topic_rows()
            .map_err(|e| self.damaged(e))?
            .into_iter()
            .map(|(id, name, _, format)| (id, (name, format == "cdr")))
            .collect();
        let mut statement = self
            .db
            .prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id")
            .map_err(|e| self.damaged(e))?;
        let mut rows = statement.query([]).map_err(|e| self.damaged(e))?;
        loop {
            let row = match rows.next() {
                Ok(Some(row)) => row,
                Ok(None) => return Ok(None),
                Err(e) => return Ok(Some(self.damaged(e))),
            };
            let fields: rusqlite::Result<(i64, i64, &[u8])> = (|| {
                let id: i64 = row.get(0)?;
                let stamp: i64 = row.get(1)?;
                let data = row.get_ref(2)?.as_blob()?;
                Ok((id, stamp, data))
            })();
            let (id, stamp, data) = match fields {
                Ok(fields) => fields,
                Err(e) => return Ok(Some(self.damaged(e))),
            };
            let Some((topic, true)) = topics.get(&id) else {
                continue;
            };
            let message = BagMessage {
                topic,
                log_time_ns: u64::try_from(stamp).unwrap_or(0),
                data,
            };
            if on_message(message).is_break() {
                return Ok(None);
            }
        }
    }
}
