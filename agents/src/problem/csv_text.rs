//! What the cost and forbidden-pairs readers share about CSV text: the delimiter a file
//! uses, and the file's line of a record (the `csv` crate counts only the lines it reads
//! records from).

/// The delimiters a cost file may use.
pub const DELIMITERS: [u8; 3] = [b',', b'\t', b';'];

/// The delimiter of the first row that is not blank or a comment: the most frequent of
/// [`DELIMITERS`] outside quotes (a comma when it has none: one column).
pub fn detect_delimiter(text: &str) -> u8 {
    let Some(line) = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
    else {
        return b',';
    };
    let mut counts = [0usize; 3];
    let mut quoted = false;
    for c in line.bytes() {
        if c == b'"' {
            quoted = !quoted;
        } else if !quoted && let Some(k) = DELIMITERS.iter().position(|&d| d == c) {
            counts[k] += 1;
        }
    }
    // Ties go to a tab or a semicolon: a comma beside one is a decimal comma (refused
    // where it is, with what to do), not the delimiter.
    let best = (0..3).fold(
        0,
        |best, k| if counts[k] >= counts[best] { k } else { best },
    );
    if counts[best] == 0 {
        b','
    } else {
        DELIMITERS[best]
    }
}

/// The 1-based line of the record the `csv` crate says starts at byte `byte` of `text`
/// (whose line starts are `starts`): past the blank and `#` comment lines it skipped.
pub fn line_at(text: &str, starts: &[usize], byte: u64) -> usize {
    let bytes = text.as_bytes();
    let mut b = byte as usize;
    loop {
        while matches!(bytes.get(b), Some(b'\n' | b'\r')) {
            b += 1;
        }
        if bytes.get(b) == Some(&b'#') {
            b += bytes[b..]
                .iter()
                .position(|&c| c == b'\n')
                .unwrap_or(bytes.len() - b);
            continue;
        }
        break;
    }
    starts.partition_point(|&s| s <= b)
}

/// Where each line of `text` starts (for [`line_at`]: the `csv` crate counts only the
/// lines it reads records from).
pub fn line_starts(text: &str) -> Vec<usize> {
    std::iter::once(0)
        .chain(text.match_indices('\n').map(|(k, _)| k + 1))
        .collect()
}
