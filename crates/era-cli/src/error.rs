//! The user's mistakes: a [`UsageError`] exits with code 2.

/// A problem with what the user asked for (a flag, a value, a path): exit code 2.
#[derive(Debug)]
pub struct UsageError(pub String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

impl era::error::InputError for UsageError {
    fn is_input_error(&self) -> bool {
        true
    }
}

/// Shorthand for returning a [`UsageError`].
pub fn usage<T>(message: impl Into<String>) -> anyhow::Result<T> {
    Err(UsageError(message.into()).into())
}
