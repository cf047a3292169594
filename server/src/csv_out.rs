//! Every CSV the server writes (scenario runs, session records, manipulability studies, class
//! results, trainees' logbooks) goes through this module: the `csv` crate does the quoting and
//! line endings, and every number
//! has one format — the shortest text that parses back to the same `f64` (Ryū, the format
//! `serde_json` also uses), e.g. `0.1`, `6890000.0`, `-3.2e-5`, `1e-7`. Non-finite values
//! are written `NaN`, `inf`, `-inf` (which Rust's `f64::from_str` reads back); absent values
//! are empty fields. Text that a spreadsheet would run as a formula — a cell starting with
//! `=`, `+`, `-`, `@`, a tab or a carriage return — is written with a leading `'`, as OWASP's
//! "CSV Injection" page recommends (names and groups are the trainees' own words).
//!
//! Rows are built whole in memory and written with one `write_all`, so a writer never leaves
//! half a row behind except when the process dies inside that call; readers of a file that
//! may have been cut take [`complete_lines`].

use std::io::{self, Write};

use seaarms_core::sim::scenario::Cell;

/// One CSV field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Field<'a> {
    /// A number, shortest round-trip text.
    Num(f64),
    /// An integer count.
    Int(u64),
    /// `true` / `false`.
    Bool(bool),
    /// Text, quoted when it needs to be.
    Text(&'a str),
    /// An absent value (empty field).
    Empty,
}

impl From<f64> for Field<'_> {
    fn from(x: f64) -> Self {
        Field::Num(x)
    }
}

impl From<Option<f64>> for Field<'_> {
    fn from(x: Option<f64>) -> Self {
        x.map_or(Field::Empty, Field::Num)
    }
}

impl From<u64> for Field<'_> {
    fn from(x: u64) -> Self {
        Field::Int(x)
    }
}

impl From<bool> for Field<'_> {
    fn from(x: bool) -> Self {
        Field::Bool(x)
    }
}

impl<'a> From<&'a str> for Field<'a> {
    fn from(x: &'a str) -> Self {
        Field::Text(x)
    }
}

impl From<Cell> for Field<'static> {
    fn from(c: Cell) -> Self {
        match c {
            Cell::Num(x) => Field::Num(x),
            Cell::Name(s) => Field::Text(s),
        }
    }
}

/// First characters that make a spreadsheet read a cell as a formula (OWASP, "CSV Injection").
const FORMULA_STARTS: [char; 6] = ['=', '+', '-', '@', '\t', '\r'];

/// A CSV writer with the one number format.
pub struct CsvOut<W: Write> {
    csv: csv::Writer<W>,
    num: ryu::Buffer,
    int: itoa::Buffer,
}

impl<W: Write> CsvOut<W> {
    /// A writer onto `w` (nothing written yet).
    pub fn new(w: W) -> CsvOut<W> {
        CsvOut {
            csv: csv::WriterBuilder::new().flexible(false).from_writer(w),
            num: ryu::Buffer::new(),
            int: itoa::Buffer::new(),
        }
    }

    /// Writes the header row.
    pub fn header<S: AsRef<str>>(&mut self, names: &[S]) -> io::Result<()> {
        self.csv
            .write_record(names.iter().map(|n| n.as_ref().as_bytes()))?;
        Ok(())
    }

    /// Writes one field of the current row.
    pub fn field(&mut self, f: Field<'_>) -> io::Result<()> {
        match f {
            Field::Num(x) => self.csv.write_field(self.num.format(x))?,
            Field::Int(x) => self.csv.write_field(self.int.format(x))?,
            Field::Bool(b) => self.csv.write_field(if b { "true" } else { "false" })?,
            Field::Text(s) if s.starts_with(FORMULA_STARTS) => {
                self.csv.write_field(format!("'{s}"))?
            }
            Field::Text(s) => self.csv.write_field(s)?,
            Field::Empty => self.csv.write_field("")?,
        }
        Ok(())
    }

    /// Ends the current row.
    pub fn end_row(&mut self) -> io::Result<()> {
        self.csv.write_record(None::<&[u8]>)?;
        Ok(())
    }

    /// Writes one whole row.
    pub fn row<'a>(&mut self, fields: impl IntoIterator<Item = Field<'a>>) -> io::Result<()> {
        for f in fields {
            self.field(f)?;
        }
        self.end_row()
    }

    /// The underlying writer (what the `csv` crate has flushed into it so far).
    pub fn get_ref(&self) -> &W {
        self.csv.get_ref()
    }

    /// Flushes and returns the underlying writer.
    pub fn into_inner(self) -> io::Result<W> {
        self.csv.into_inner().map_err(|e| {
            let kind = e.error().kind();
            io::Error::new(kind, e.error().to_string())
        })
    }
}

/// A whole CSV table in memory: the header, then one line per row (writing to memory cannot
/// fail). The studies' tables are built with this.
pub fn table<'a, R>(header: &[&str], rows: impl IntoIterator<Item = R>) -> String
where
    R: IntoIterator<Item = Field<'a>>,
{
    let mut out = CsvOut::new(Vec::new());
    // Writing into a Vec only fails on allocation failure, which aborts anyway.
    let _ = out.header(header);
    for r in rows {
        let _ = out.row(r);
    }
    let bytes = out.into_inner().unwrap_or_default();
    // Fields are UTF-8 text and ASCII numbers: the table is UTF-8.
    String::from_utf8(bytes).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned())
}

/// A whole CSV table of serializable rows (structs whose fields are numbers, booleans,
/// strings or `Option`s of them): the given columns, taken from each row by field name, in
/// the given order. Fields not named are left out (e.g. vectors that a JSON document carries
/// but the table does not); a named field that is absent or `None` is an empty field.
pub fn table_of<T: serde::Serialize>(columns: &[&str], rows: &[T]) -> String {
    let values: Vec<serde_json::Map<String, serde_json::Value>> = rows
        .iter()
        .map(|r| match serde_json::to_value(r) {
            Ok(serde_json::Value::Object(m)) => m,
            _ => serde_json::Map::new(),
        })
        .collect();
    table(
        columns,
        values.iter().map(|m| {
            columns.iter().map(|c| match m.get(*c) {
                Some(serde_json::Value::Number(n)) => match n.as_u64() {
                    Some(i) => Field::Int(i),
                    None => n.as_f64().map_or(Field::Empty, Field::Num),
                },
                Some(serde_json::Value::Bool(b)) => Field::Bool(*b),
                Some(serde_json::Value::String(s)) => Field::Text(s),
                _ => Field::Empty,
            })
        }),
    )
}

/// The part of `bytes` up to and including its last newline: what a reader may take from a
/// CSV another thread or a crashed process may have left mid-row.
pub fn complete_lines(bytes: &[u8]) -> &[u8] {
    match bytes.iter().rposition(|&b| b == b'\n') {
        Some(i) => &bytes[..=i],
        None => &[],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Shortest round-trip: every number parses back to the very same f64 (bit for bit, ±0
    /// included), and text fields are quoted by the `csv` crate and read back verbatim.
    #[test]
    fn numbers_round_trip_and_text_is_quoted() {
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut values = vec![
            0.0,
            -0.0,
            0.1,
            1.0 / 3.0,
            6.89e6,
            1e-7,
            -3.2e-5,
            f64::MAX,
            5e-324,
        ];
        for _ in 0..2000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let x = f64::from_bits(state);
            if x.is_finite() {
                values.push(x);
            }
        }
        let text = table(
            &["x", "label", "maybe"],
            values
                .iter()
                .map(|&x| [Field::Num(x), Field::Text("a,\"b\""), Field::Empty]),
        );
        let mut r = csv::Reader::from_reader(text.as_bytes());
        let mut n = 0;
        for (rec, &x) in r.records().zip(&values) {
            let rec = rec.expect("row");
            let back: f64 = rec[0].parse().expect("number");
            assert_eq!(back.to_bits(), x.to_bits(), "{x:e} written as {}", &rec[0]);
            assert_eq!(&rec[1], "a,\"b\"");
            assert_eq!(&rec[2], "");
            n += 1;
        }
        assert_eq!(n, values.len());
    }

    #[test]
    fn non_finite_values_read_back() {
        let text = table(
            &["x"],
            [
                [Field::Num(f64::NAN)],
                [Field::Num(f64::INFINITY)],
                [Field::Num(f64::NEG_INFINITY)],
            ],
        );
        let back: Vec<f64> = text
            .lines()
            .skip(1)
            .map(|l| l.parse().expect("parses"))
            .collect();
        assert!(back[0].is_nan());
        assert_eq!(back[1], f64::INFINITY);
        assert_eq!(back[2], f64::NEG_INFINITY);
    }

    /// The studies' row type in miniature: named columns in the given order, `None` empty,
    /// a vector not among the columns left out, text quoted; numbers exact.
    #[test]
    fn table_of_serializable_rows() {
        #[derive(serde::Serialize)]
        struct R {
            series: String,
            x: f64,
            reachable: bool,
            hong: Option<f64>,
            q: Option<Vec<f64>>,
        }
        let rows = [
            R {
                series: "dual, x".into(),
                x: 0.1 + 0.2,
                reachable: true,
                hong: Some(1e-7),
                q: Some(vec![1.0, 2.0]),
            },
            R {
                series: "s".into(),
                x: -2.5,
                reachable: false,
                hong: None,
                q: None,
            },
        ];
        let text = table_of(&["series", "reachable", "x", "hong"], &rows);
        assert_eq!(
            text,
            "series,reachable,x,hong\n\"dual, x\",true,0.30000000000000004,1e-7\ns,false,-2.5,\n"
        );
    }

    #[test]
    fn complete_lines_drops_a_cut_row() {
        assert_eq!(complete_lines(b"a,b\n1,2\n3,"), b"a,b\n1,2\n");
        assert_eq!(complete_lines(b"a,b\n1,2\n"), b"a,b\n1,2\n");
        assert_eq!(complete_lines(b"a,b"), b"");
    }

    /// OWASP "CSV Injection": a text cell never starts with `=`, `+`, `-`, `@`, tab or CR
    /// (the hostile names), other text and numbers are untouched, and the `csv`
    /// crate reads the neutralised cell back as the name with one `'` before it.
    #[test]
    fn formula_cells_are_neutralised() {
        let hostile = [
            "=HYPERLINK(\"http://evil\",\"x\")",
            "+cmd|' /C calc'!A0",
            "-2+3",
            "@SUM(1,2)",
            "\tx",
            "\rx",
        ];
        let text = table(
            &["name", "n"],
            hostile
                .iter()
                .map(|h| [Field::Text(h), Field::Num(-1.5)])
                .chain([[Field::Text("Ann =1"), Field::Num(2.0)]]),
        );
        let mut r = csv::Reader::from_reader(text.as_bytes());
        let rows: Vec<csv::StringRecord> = r.records().map(|r| r.unwrap()).collect();
        for (row, h) in rows.iter().zip(hostile) {
            assert_eq!(&row[0], format!("'{h}"));
            assert_eq!(&row[1], "-1.5", "numbers stay numbers");
        }
        assert_eq!(&rows[hostile.len()][0], "Ann =1");
        for line in text.lines().skip(1) {
            let first = line.trim_start_matches('"').chars().next();
            assert!(!matches!(first, Some('=' | '+' | '@' | '\t')), "{line:?}");
        }
    }
}
