//! Line-based CSV text (points files, recordings) read with the csv crate: one record per
//! line (no quoting), fields trimmed, each record with its 1-based line for errors.
//!
//! csv's own line count leaves out the empty lines it skips, so the line is counted here
//! from each record's byte offset (where the reader started it: before those empty lines).

use csv::StringRecord;

/// The records of `text`, each with its line.
pub struct Records<'t> {
    text: &'t str,
    reader: csv::StringRecordsIntoIter<&'t [u8]>,
    /// Where the last record started, and its line.
    offset: usize,
    line: usize,
}

impl<'t> Records<'t> {
    /// Reads `text` (a byte-order mark already removed).
    pub fn new(text: &'t str) -> Records<'t> {
        let reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .quoting(false)
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes())
            .into_records();
        Records {
            text,
            reader,
            offset: 0,
            line: 1,
        }
    }
}

impl Iterator for Records<'_> {
    /// A record and its line, or the line the reader failed at and why.
    type Item = Result<(usize, StringRecord), (usize, String)>;

    fn next(&mut self) -> Option<Self::Item> {
        let record = match self.reader.next()? {
            Ok(record) => record,
            Err(e) => return Some(Err((self.line, e.to_string()))),
        };
        let from = record
            .position()
            .map_or(self.offset, |p| {
                usize::try_from(p.byte()).unwrap_or(usize::MAX)
            })
            .clamp(self.offset, self.text.len());
        let skipped = self.text[from..]
            .bytes()
            .take_while(|b| matches!(b, b'\r' | b'\n'))
            .count();
        let start = from + skipped;
        self.line += self.text[self.offset..start].matches('\n').count();
        self.offset = start;
        Some(Ok((self.line, record)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(text: &str) -> Vec<(usize, Vec<String>)> {
        Records::new(text)
            .map(|r| r.map(|(line, rec)| (line, rec.iter().map(String::from).collect())))
            .collect::<Result<_, _>>()
            .unwrap_or_default()
    }

    #[test]
    fn lines_count_the_empty_lines_the_reader_skips() {
        let found = lines("\n\n x , y \r\n0,0.2\r\n\r\n  \n1,\"2\"");
        let expected: Vec<(usize, Vec<String>)> = vec![
            (3, vec!["x".into(), "y".into()]),
            (4, vec!["0".into(), "0.2".into()]),
            (6, vec![String::new()]),
            (7, vec!["1".into(), "\"2\"".into()]),
        ];
        assert_eq!(found, expected);
    }
}
