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
