//! Text in fixed-size, NUL-padded UTF-8 byte arrays (names and messages in
//! the message layouts).

/// The text before the first NUL, up to the last whole character: invalid
/// UTF-8 ends the text where it starts, and a full array (no NUL) is text
/// to its end.
pub(crate) fn text_of(bytes: &[u8]) -> &str {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    match std::str::from_utf8(&bytes[..end]) {
        Ok(text) => text,
        Err(err) => std::str::from_utf8(&bytes[..err.valid_up_to()]).unwrap_or_default(),
    }
}

/// Copies as much of `text` as fits (whole characters) into `to`, leaving
/// the rest of `to` as it was: clear it first.
pub(crate) fn write_text(to: &mut [u8], text: &str) {
    let mut end = text.len().min(to.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    to[..end].copy_from_slice(&text.as_bytes()[..end]);
}
