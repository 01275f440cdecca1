//! Text helpers shared by the CSV readers: `# key: value` metadata lines and the header.

use std::collections::BTreeMap;

/// A `# key: value` metadata line as (lower-case key, value); `None` for other lines
/// (a `#` line without a colon is a plain comment).
/// The `# key: value` lines before a CSV header (keys lower-case; blank lines skipped)
/// and the header itself as (1-based line number, trimmed text), if there is one.
pub fn metadata_and_header(text: &str) -> (BTreeMap<String, String>, Option<(usize, &str)>) {
    let mut metadata = BTreeMap::new();
    for (index, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.is_empty() {
            continue;
        }
        if trimmed.starts_with('#') {
            if let Some((key, value)) = metadata_line(trimmed) {
                metadata.insert(key, value);
            }
            continue;
        }
        return (metadata, Some((index + 1, trimmed)));
    }
    (metadata, None)
}

pub fn metadata_line(trimmed: &str) -> Option<(String, String)> {
    let (key, value) = trimmed.strip_prefix('#')?.split_once(':')?;
    Some((key.trim().to_ascii_lowercase(), value.trim().to_string()))
}

/// Text from a file made safe to echo in a message: control characters (C0, DEL, C1,
/// such as ESC), the byte-order mark and zero-width or direction-changing characters
/// are shown as `\u{1b}`, `\u{feff}`, …; everything else is kept.
pub fn escaped(text: &str) -> String {
    escape(text, false)
}

/// [`escaped`] keeping line breaks: for whole messages, which may span lines.
pub fn escaped_message(text: &str) -> String {
    escape(text, true)
}

fn escape(text: &str, keep_newlines: bool) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if keep_newlines && c == '\n' {
            out.push(c);
            continue;
        }
        let invisible = matches!(
            c,
            '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2060}'..='\u{2064}' | '\u{feff}'
        );
        if c.is_control() || invisible {
            out.push_str(&format!("\\u{{{:x}}}", c as u32));
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controls_and_invisible_characters_are_shown() {
        assert_eq!(escaped("a\u{1b}[2Jb"), "a\\u{1b}[2Jb");
        assert_eq!(escaped("\u{feff}time_s"), "\\u{feff}time_s");
        assert_eq!(escaped("x\u{200b}\u{9b}\ty"), "x\\u{200b}\\u{9b}\\u{9}y");
        assert_eq!(escaped("Hz µm/s²"), "Hz µm/s²");
        assert_eq!(escaped_message("a\nb\u{7}"), "a\nb\\u{7}");
    }
}
