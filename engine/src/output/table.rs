//! CSV tables through the `csv` crate: rows of cells that the caller formats (numbers with
//! `{:e}`, so that they read back bit for bit), joined and quoted by the writer (a cell holding
//! a comma, a quote or a line break is quoted, quotes doubled), one `\n` per row; and read back
//! by name of column.

use crate::error::EngineError;

/// A CSV table being written: rows of equal length, the header first.
pub(crate) struct Table {
    writer: csv::Writer<Vec<u8>>,
}

impl Table {
    /// A table whose first row is `header`.
    pub(crate) fn new<S: AsRef<[u8]>>(header: impl IntoIterator<Item = S>) -> Self {
        let mut table = Self {
            writer: csv::Writer::from_writer(Vec::new()),
        };
        table.row(header);
        table
    }

    /// Appends a row.
    ///
    /// # Panics
    /// When the row's length is not the header's: the writing code is wrong.
    pub(crate) fn row<S: AsRef<[u8]>>(&mut self, cells: impl IntoIterator<Item = S>) {
        (self.writer.write_record(cells)).expect("a row as long as the header, into memory");
    }

    /// The text of the table.
    pub(crate) fn into_text(self) -> String {
        let bytes = (self.writer.into_inner()).unwrap_or_else(|_| unreachable!("memory"));
        String::from_utf8(bytes).expect("cells of text")
    }
}

/// One CSV line (with its `\n`) of `cells`, for tables that grow a line at a time.
pub(crate) fn line<S: AsRef<[u8]>>(cells: impl IntoIterator<Item = S>) -> String {
    Table::new(cells).into_text()
}

/// A CSV table read back: its header and its rows of text cells. Rows may be shorter or longer
/// than the header (a cell that is not there reads as missing).
pub(crate) struct ReadTable {
    header: Vec<String>,
    rows: Vec<csv::StringRecord>,
}

impl ReadTable {
    /// The table of `text` (header on the first line); errors name the `source` file.
    pub(crate) fn parse(text: &str, source: &str) -> Result<Self, EngineError> {
        let invalid = |e: csv::Error| EngineError::Input(format!("{source}: not CSV: {e}"));
        let mut reader = csv::ReaderBuilder::new()
            .flexible(true)
            .from_reader(text.as_bytes());
        let header = reader.headers().map_err(invalid)?;
        let header = header.iter().map(str::to_owned).collect();
        let rows = reader
            .records()
            .collect::<Result<_, _>>()
            .map_err(invalid)?;
        Ok(Self { header, rows })
    }

    /// The index of the column `name`, if the header has it.
    pub(crate) fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The rows, each a list of cells.
    pub(crate) fn rows(&self) -> impl Iterator<Item = &csv::StringRecord> {
        self.rows.iter()
    }
}

/// The number in `cell`, NaN when it is missing or not a number.
pub(crate) fn number(cell: Option<&str>) -> f64 {
    cell.and_then(|c| c.parse().ok()).unwrap_or(f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_joined_quoted_where_needed_and_read_back() {
        let mut table = Table::new(["t_s", "tag", "note"]);
        table.row([format!("{:e}", 1.5e-6), "crack".into(), String::new()]);
        table.row(["-0e0", "a, b", "say \"x\""]);
        let text = table.into_text();
        assert_eq!(
            text,
            "t_s,tag,note\n1.5e-6,crack,\n-0e0,\"a, b\",\"say \"\"x\"\"\"\n"
        );
        assert_eq!(line(["1", "2"]), "1,2\n");
        let read = ReadTable::parse(&format!("{text}3e0\n"), "test.csv").unwrap();
        assert_eq!((read.column("tag"), read.column("speed")), (Some(1), None));
        let rows: Vec<_> = read.rows().collect();
        assert_eq!(rows.len(), 3);
        assert_eq!(number(rows[0].get(0)), 1.5e-6);
        assert_eq!(&rows[1][1], "a, b");
        assert_eq!(&rows[1][2], "say \"x\"");
        assert!(number(rows[2].get(1)).is_nan() && number(rows[0].get(1)).is_nan());
    }
}
