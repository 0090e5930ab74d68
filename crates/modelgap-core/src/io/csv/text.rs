//! The text under the CSV parser: lines checked as UTF-8, comments and blank lines emptied,
//! the separator detected, and each record's line found and its quoting checked (the
//! `csv` crate accepts stray quotes that a recording should not have).

use std::io::Read;

use crate::error::{CoreError, Result};

/// The whole text, checked as UTF-8 line by line, without a byte-order mark, with comment
/// and blank lines emptied (their line ends kept, so the parser's line numbers hold).
pub(super) fn clean_text(mut reader: impl Read) -> Result<String> {
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|e| CoreError::io(e, None))?;
    let mut text = String::with_capacity(bytes.len());
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = std::str::from_utf8(raw).map_err(|_| CoreError::NotUtf8 {
            line: i + 1,
            path: None,
        })?;
        let line = if i == 0 {
            line.strip_prefix('\u{feff}').unwrap_or(line)
        } else {
            text.push('\n');
            line
        };
        let trimmed = line.trim();
        if !(trimmed.is_empty() || trimmed.starts_with('#')) {
            text.push_str(line);
        }
    }
    Ok(text)
}

/// Checks a declared delimiter.
pub(super) fn check_delimiter(delimiter: u8) -> Result<u8> {
    if matches!(delimiter, b'"' | b'\n' | b'\r' | b'#' | b'.' | b'-' | b'+')
        || delimiter.is_ascii_alphanumeric()
        || !delimiter.is_ascii()
    {
        return Err(CoreError::InvalidArgument {
            name: "delimiter",
            reason: format!(
                "`{}` cannot separate cells: it can be part of a number, a quote or a line end",
                char::from(delimiter).escape_default()
            ),
        });
    }
    Ok(delimiter)
}

/// `,`, unless the header has no `,` outside quotes and has `;` (then `;`) or a tab.
pub(super) fn detect_delimiter(header: &str) -> u8 {
    let mut quoted = false;
    let (mut commas, mut semicolons, mut tabs) = (0, 0, 0);
    for b in header.bytes() {
        match b {
            b'"' => quoted = !quoted,
            b',' if !quoted => commas += 1,
            b';' if !quoted => semicolons += 1,
            b'\t' if !quoted => tabs += 1,
            _ => {}
        }
    }
    if commas == 0 && semicolons > 0 {
        b';'
    } else if commas == 0 && tabs > 0 {
        b'\t'
    } else {
        b','
    }
}

/// The line a record starts on (from 1), after checking its quoting.
///
/// The parser's position is where it started reading, before any blank lines (and the `\n`
/// of a `\r\n`) it skipped; the record starts after them.
pub(super) fn check_record(
    record: &::csv::StringRecord,
    text: &str,
    delimiter: u8,
) -> Result<usize> {
    let (mut line, mut start) = record.position().map_or((1, 0), |p| {
        (
            usize::try_from(p.line()).unwrap_or(usize::MAX),
            usize::try_from(p.byte()).unwrap_or(usize::MAX),
        )
    });
    let bytes = text.as_bytes();
    while let Some(&b) = bytes.get(start)
        && (b == b'\n' || b == b'\r')
    {
        if b == b'\n' {
            line += 1;
        }
        start += 1;
    }
    if let Some(cell) = record.iter().position(|c| c.contains(['\n', '\r'])) {
        return Err(CoreError::CsvQuoting {
            line,
            cell: cell + 1,
            reason: "a quoted cell runs past the end of the line (a missing closing quote?)",
            path: None,
        });
    }
    let raw = text.get(start..).unwrap_or_default();
    let raw = raw.split('\n').next().unwrap_or_default();
    check_quoting(raw.trim_end_matches('\r'), delimiter).map_err(|(cell, reason)| {
        CoreError::CsvQuoting {
            line,
            cell,
            reason,
            path: None,
        }
    })?;
    Ok(line)
}

/// Checks the quotes of one line: a cell is unquoted and holds no quote, or is quoted from
/// its first character to its closing quote (spaces may follow), with `""` inside. Returns
/// the cell (from 1) and the reason when it is not.
fn check_quoting(raw: &str, delimiter: u8) -> std::result::Result<(), (usize, &'static str)> {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        Start,
        Spaces,
        Unquoted,
        Quoted,
        Closed,
    }
    if !raw.contains('"') {
        return Ok(());
    }
    let mut state = State::Start;
    let mut cell = 1;
    for b in raw.bytes() {
        if b == delimiter && state != State::Quoted {
            cell += 1;
            state = State::Start;
            continue;
        }
        let space = b == b' ' || b == b'\t';
        state = match (state, b) {
            (State::Start | State::Spaces, _) if space => State::Spaces,
            (State::Start, b'"') => State::Quoted,
            (State::Spaces, b'"') => {
                return Err((cell, "a quote after spaces: the quote must open the cell"));
            }
            (State::Unquoted, b'"') => {
                return Err((
                    cell,
                    "a quote inside an unquoted cell (quote the whole cell and double the quote)",
                ));
            }
            (State::Start | State::Spaces | State::Unquoted, _) => State::Unquoted,
            (State::Quoted, b'"') => State::Closed,
            (State::Quoted, _) => State::Quoted,
            (State::Closed, b'"') => State::Quoted,
            (State::Closed, _) if space => State::Closed,
            (State::Closed, _) => return Err((cell, "text after the closing quote")),
        };
    }
    if state == State::Quoted {
        return Err((cell, "a quoted cell without its closing quote"));
    }
    Ok(())
}
