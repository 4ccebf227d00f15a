//! Errors as one line of text.
//!
//! Errors that keep their cause (an io, serde or iceoryx2 error) as a `source` do not repeat
//! it in their message; the command line prints the whole chain on one line, and code that
//! must turn an error into text (an agent's log line, an error of an exchange) uses
//! [`one_line`].

/// `error`'s message followed by its sources', separated by `: `.
pub fn one_line(error: &(dyn std::error::Error + 'static)) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(cause) = source {
        text.push_str(": ");
        text.push_str(&cause.to_string());
        source = cause.source();
    }
    text
}
