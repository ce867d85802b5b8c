//! The ROS 2 names and numbers `slope-ros2` takes (flags and the config
//! file's `[ros2]`), checked as ROS 2 checks them: namespaces, node names,
//! TF frame ids and DDS domain ids. Here, not in `slope-ros2`, so that the
//! config file is checked whole by every daemon.

/// The largest DDS domain id: RTPS's port numbers (7400 + 250 * domain +
/// ...) must stay below 65536 (ROS 2 documents 0-232, 0-101 without
/// clashes with Linux's ephemeral ports).
pub const MAX_DOMAIN_ID: u16 = 232;

/// A ROS 2 namespace: `/`, or `/` and tokens separated by `/`, each of
/// letters, digits and `_`, starting with a letter or `_`, without `__`;
/// no trailing `/`.
pub fn namespace_arg(text: &str) -> Result<String, String> {
    let usable = text == "/"
        || text
            .strip_prefix('/')
            .is_some_and(|rest| rest.split('/').all(is_name_token));
    if usable {
        Ok(text.to_string())
    } else {
        Err(format!(
            "'{text}' is not a ROS 2 namespace: expected / or /NAME[/NAME...] with names of \
             letters, digits and _ (starting with a letter or _, no __), e.g. /robot1"
        ))
    }
}

/// A ROS 2 node name: one token of letters, digits and `_`, starting with
/// a letter or `_`, without `__`.
pub fn node_name_arg(text: &str) -> Result<String, String> {
    if is_name_token(text) {
        Ok(text.to_string())
    } else {
        Err(format!(
            "'{text}' is not a ROS 2 node name: expected letters, digits and _ (starting with a \
             letter or _, no __), e.g. slope_ros2"
        ))
    }
}

/// A TF frame id: not empty, no whitespace, no leading `/` (tf2 refuses
/// it).
pub fn frame_id_arg(text: &str) -> Result<String, String> {
    if text.is_empty() || text.starts_with('/') || text.contains(char::is_whitespace) {
        Err(format!(
            "'{text}' is not a TF frame id: expected a name without spaces and without a \
             leading /, e.g. base_link"
        ))
    } else {
        Ok(text.to_string())
    }
}

/// A DDS domain id from 0 to [`MAX_DOMAIN_ID`].
pub fn check_domain_id(id: u16) -> Result<u16, String> {
    if id <= MAX_DOMAIN_ID {
        Ok(id)
    } else {
        Err(format!("must be a DDS domain id from 0 to {MAX_DOMAIN_ID}"))
    }
}

fn is_name_token(token: &str) -> bool {
    token.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
        && token.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !token.contains("__")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_the_ros_2_rules() {
        for good in ["/", "/robot1", "/a/b_c", "/_x"] {
            assert_eq!(namespace_arg(good).as_deref(), Ok(good));
        }
        for bad in [
            "", "robot1", "/robot1/", "//", "/1robot", "/a__b", "/a-b", "/a b",
        ] {
            let err = namespace_arg(bad).unwrap_err();
            assert!(err.contains("not a ROS 2 namespace"), "{bad}: {err}");
        }
        assert!(node_name_arg("slope_ros2").is_ok());
        for bad in ["", "slope-ros2", "2slope", "a/b"] {
            assert!(node_name_arg(bad).is_err(), "{bad}");
        }
        assert!(frame_id_arg("base_link").is_ok());
        for bad in ["", "/base_link", "base link"] {
            assert!(frame_id_arg(bad).is_err(), "{bad}");
        }
        assert_eq!(check_domain_id(232), Ok(232));
        assert!(check_domain_id(233).is_err());
    }
}
