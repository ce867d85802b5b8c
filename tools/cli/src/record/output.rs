//! The output directory of a recording, checked (and made) before
//! anything is waited for.

use std::path::Path;

use anyhow::Context;

/// Makes sure `dir` can take a new recording before anything is waited
/// for: an empty directory, or one that does not exist yet in a directory
/// that does (then created; a typing error in a parent is refused, not
/// created). Returns whether it was created.
pub fn prepare_out_dir(dir: &Path) -> anyhow::Result<bool> {
    match std::fs::read_dir(dir) {
        Ok(mut entries) => {
            if entries.next().is_some() {
                anyhow::bail!(
                    "the output directory {} is not empty; give a new or empty directory",
                    dir.display()
                );
            }
            Ok(false)
        }
        // Nothing there, or a parent that is a file (said so by check_parent).
        Err(err)
            if matches!(
                err.kind(),
                std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
            ) =>
        {
            check_parent(dir, "the output directory ")?;
            std::fs::create_dir(dir)
                .with_context(|| format!("cannot create the output directory {}", dir.display()))?;
            Ok(true)
        }
        Err(err) => Err(err).with_context(|| {
            format!(
                "cannot use {} as the output directory (is it a file, or unreadable?)",
                dir.display()
            )
        }),
    }
}

/// Refuses an output (`what` names it in the message) whose directory does
/// not exist: a typing error in a parent is said, not created.
pub(super) fn check_parent(path: &Path, what: &str) -> anyhow::Result<()> {
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(parent) = parent.filter(|p| !p.is_dir()) {
        anyhow::bail!(
            "cannot create {what}{}: {}",
            path.display(),
            crate::mcap_export::not_a_directory(parent)
        );
    }
    Ok(())
}

pub(super) fn is_empty_dir(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|mut entries| entries.next().is_none())
}
