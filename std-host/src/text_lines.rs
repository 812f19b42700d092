//! Line numbers for error messages: of CSV rows from byte offsets, and of the first byte that
//! is not UTF-8 in a text file (the standard library's message names neither).
//!
//! The `csv` crate's record positions carry a line count that loses one line per CRLF: after a
//! `\r\n` it places the next record at the line feed, before counting it. Error messages that
//! name a row's line count the line ends themselves.

/// The 1-based line of the row the CSV reader places at byte `at`: one more than the line ends
/// (LF, CRLF or a lone CR, as the reader takes them) before its first byte. The reader's own line
/// count is not used: after a CRLF it places the next row at the line feed and counts one line
/// too few (a row on line 3 of a CRLF file was reported on line 2), so line-end bytes at `at`
/// are skipped first.
pub fn line_at(text: &[u8], at: u64) -> u64 {
    let mut at = usize::try_from(at).unwrap_or(usize::MAX).min(text.len());
    while matches!(text.get(at), Some(b'\r' | b'\n')) {
        at += 1;
    }
    let before = &text[..at];
    let feeds = before.iter().filter(|&&b| b == b'\n').count();
    let lone_cr = |w: &[u8]| w[0] == b'\r' && w.get(1).is_none_or(|&b| b != b'\n');
    let returns = before.windows(2).filter(|w| lone_cr(w)).count()
        + usize::from(before.last() == Some(&b'\r'));
    1 + (feeds + returns) as u64
}

/// Where a file's bytes stop being UTF-8.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NotUtf8 {
    /// The 1-based line (counting line feeds) of the first bad byte.
    pub line: usize,
    /// Its 0-based byte offset in the file.
    pub byte: usize,
}

impl core::fmt::Display for NotUtf8 {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let Self { line, byte } = self;
        write!(
            f,
            "not UTF-8 text: line {line} (byte {byte}) holds a byte that is not UTF-8"
        )
    }
}

/// The bytes as text, or where the first byte that is not UTF-8 lies.
pub fn utf8_text(bytes: Vec<u8>) -> Result<String, NotUtf8> {
    String::from_utf8(bytes).map_err(|e| {
        let byte = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..byte].iter().filter(|&&b| b == b'\n').count() + 1;
        NotUtf8 { line, byte }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where the CSV reader places each row of a file, and the line this names.
    fn lines_of_rows(text: &str) -> Vec<u64> {
        let mut csv = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .from_reader(text.as_bytes());
        csv.records()
            .map(|r| line_at(text.as_bytes(), r.unwrap().position().unwrap().byte()))
            .collect()
    }

    #[test]
    fn every_line_end_counts_once() {
        assert_eq!(lines_of_rows("a\nb\nc\n"), [1, 2, 3]);
        assert_eq!(lines_of_rows("a\r\nb\r\nc\r\n"), [1, 2, 3]);
        assert_eq!(lines_of_rows("a\rb\rc"), [1, 2, 3]);
        assert_eq!(lines_of_rows("\n\r\na\r\n\r\nb\n\rc\r"), [3, 5, 7]);
        assert_eq!(lines_of_rows("a\r\r\nb"), [1, 3]);
        // Past the end: the line after the last line end.
        assert_eq!(line_at(b"a\nb\n", 99), 3);
    }

    #[test]
    fn the_first_bad_byte_is_located() {
        assert_eq!(utf8_text(b"a\nb\n".to_vec()).as_deref(), Ok("a\nb\n"));
        let at = utf8_text(b"a\nb\nc\xff\n".to_vec()).unwrap_err();
        assert_eq!(at, NotUtf8 { line: 3, byte: 5 });
        assert!(at.to_string().contains("line 3 (byte 5)"), "{at}");
    }
}
