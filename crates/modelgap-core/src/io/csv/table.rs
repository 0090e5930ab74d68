//! The table behind a CSV recording: the header (time column, units, a row index), an
//! optional unit row, then the rows, each number's decimal mark checked against the file's.

use super::{CsvOptions, CsvRecording};
use crate::error::{CoreError, Location, Result};
use crate::io::columns::{
    check_magnitude, check_signal_names, find_time, is_index_name, next_row_number, per_second,
    row_index_note, split_unit,
};
use crate::recording::{Recording, Signal};

/// Why an unnamed first column is refused when its values are not a row index.
const UNNAMED_INDEX: &str = "an unnamed first column is read as a row index, and left out, \
                             only when its values are consecutive whole numbers";

/// A unit as a unit row writes it: `V`, `[V]` or `(V)`; `None` for an empty cell.
fn unit_cell(cell: &str) -> Option<String> {
    let unit = cell
        .strip_prefix('[')
        .and_then(|c| c.strip_suffix(']'))
        .or_else(|| cell.strip_prefix('(').and_then(|c| c.strip_suffix(')')))
        .unwrap_or(cell)
        .trim();
    (!unit.is_empty()).then(|| unit.to_owned())
}

/// The decimal mark of a file's numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Decimal {
    /// `1.5`; a comma in a number is refused (`why` says so).
    Point { why: &'static str },
    /// `1,5`, declared; a point in a number is refused.
    Comma,
    /// Either, the first number with a mark deciding: `(mark, line)` once one has.
    Detect(Option<(char, usize)>),
}

/// The header, the columns read so far and what the rows have shown.
pub(super) struct Table {
    /// The header cells as written.
    cells: Vec<String>,
    /// The name of each column (a header cell without its unit).
    names: Vec<String>,
    /// The unit of each column, from the header or the unit row.
    units: Vec<Option<String>>,
    time: usize,
    /// How many time units make a second (1 for seconds or no unit).
    time_per_second: f64,
    /// The first column, while it may be a row index.
    index: Option<IndexColumn>,
    delimiter: u8,
    decimal: Decimal,
    t: Vec<f64>,
    /// The values of each column; the time column's stays empty.
    columns: Vec<Vec<f64>>,
    /// Whether a data row has been read (a unit row may only come before).
    rows_started: bool,
    notes: Vec<String>,
}

/// A first column that may be a row index.
struct IndexColumn {
    /// The line of the first row whose value does not follow, if any.
    broken_at: Option<usize>,
    first: Option<f64>,
    last: Option<f64>,
    /// Its first error as a signal, raised only if it turns out to be one.
    error: Option<CoreError>,
}

impl Table {
    /// The table a header starts: its time column found, its names checked.
    pub(super) fn new(
        cells: &[&str],
        line: usize,
        options: &CsvOptions,
        delimiter: u8,
    ) -> Result<Table> {
        let time = find_time(cells, Some(line), options.time.as_deref())?;
        let (names, units): (Vec<String>, Vec<Option<String>>) = cells
            .iter()
            .map(|c| {
                let (name, unit) = split_unit(c);
                (name.to_owned(), unit.map(str::to_owned))
            })
            .unzip();
        let index =
            (time != 0 && cells.len() > 1 && is_index_name(cells[0])).then(|| IndexColumn {
                broken_at: None,
                first: None,
                last: None,
                error: None,
            });
        // The time column is no signal, nor an unnamed first column that may be a row index.
        check_signal_names(
            names
                .iter()
                .enumerate()
                .filter(|&(i, name)| i != time && !(i == 0 && index.is_some() && name.is_empty()))
                .map(|(_, name)| name.as_str()),
            Some(Location::Line(line)),
        )?;
        let decimal = match (options.decimal_comma, delimiter) {
            (Some(true), _) => Decimal::Comma,
            (Some(false), _) => Decimal::Point {
                why: "decimal commas are declared off; write the number with `.`",
            },
            (None, b',') => Decimal::Point {
                why: "a decimal comma, but cells are separated by `,`: declare decimal commas \
                      (`--decimal-comma`) to read it, or separate cells with `;`",
            },
            (None, _) => Decimal::Detect(None),
        };
        let mut table = Table {
            cells: cells.iter().map(|c| (*c).to_owned()).collect(),
            names,
            units,
            time,
            time_per_second: 1.0,
            index,
            delimiter,
            decimal,
            t: Vec::new(),
            columns: vec![Vec::new(); cells.len()],
            rows_started: false,
            notes: Vec::new(),
        };
        table.set_time_unit(line)?;
        Ok(table)
    }

    /// Takes the time column's unit, from the header or the unit row at `line`.
    fn set_time_unit(&mut self, line: usize) -> Result<()> {
        if let Some(unit) = &self.units[self.time] {
            self.time_per_second = per_second(unit).ok_or_else(|| CoreError::TimeUnit {
                line: Some(line),
                column: self.cells[self.time].clone(),
                unit: unit.clone(),
                path: None,
            })?;
        }
        Ok(())
    }

    /// Reads a row: the unit row, right after the header, or a sample.
    pub(super) fn push_row(&mut self, cells: &[&str], line: usize) -> Result<()> {
        if cells.len() != self.cells.len() {
            return Err(CoreError::RowLength {
                line,
                expected: self.cells.len(),
                found: cells.len(),
                path: None,
            });
        }
        if !self.rows_started && self.is_unit_row(cells) {
            for (i, cell) in cells.iter().enumerate() {
                if self.units[i].is_none() && !(i == 0 && self.index.is_some()) {
                    self.units[i] = unit_cell(cell);
                }
            }
            self.set_time_unit(line)?;
            self.notes
                .push(format!("line {line} read as the columns' units"));
            self.rows_started = true;
            return Ok(());
        }
        self.rows_started = true;
        let t = self.number(cells[self.time], self.time, line)? / self.time_per_second;
        let column = &self.cells[self.time];
        if !t.is_finite() {
            return Err(CoreError::NonFinite {
                at: Location::Line(line),
                column: column.clone(),
                value: t,
                path: None,
            });
        }
        check_magnitude(t, t, column, Location::Line(line))?;
        if let Some(&t_prev) = self.t.last()
            && t <= t_prev
        {
            return Err(CoreError::NonIncreasingTime {
                at: Location::Line(line),
                t_prev,
                t,
                path: None,
            });
        }
        self.t.push(t);
        for (i, cell) in cells.iter().enumerate() {
            if i == self.time {
                continue;
            }
            let value = self.value(cell, i, t, line);
            if i == 0
                && let Some(index) = &mut self.index
            {
                index.follow(cell, line);
                if index.broken_at.is_none() {
                    // Still a row index: an error counts only if it turns out a signal.
                    let value = value.unwrap_or_else(|e| {
                        index.error.get_or_insert(e);
                        0.0
                    });
                    self.columns[0].push(value);
                    continue;
                }
                if self.names[0].is_empty() {
                    return Err(CoreError::InvalidSignalName {
                        name: String::new(),
                        reason: UNNAMED_INDEX,
                        at: Some(Location::Line(line)),
                        path: None,
                    });
                }
                if let Some(error) = index.error.take() {
                    return Err(error);
                }
            }
            self.columns[i].push(value?);
        }
        Ok(())
    }

    /// True for a row right after the header where no cell is a number and some cell is not
    /// empty: the columns' units.
    fn is_unit_row(&self, cells: &[&str]) -> bool {
        cells.iter().any(|c| !c.is_empty())
            && cells.iter().all(|c| {
                c.parse::<f64>().is_err() && c.replacen(',', ".", 1).parse::<f64>().is_err()
            })
    }

    /// The value of a signal cell: a finite number within [`MAX_MAGNITUDE`].
    fn value(&mut self, cell: &str, col: usize, t: f64, line: usize) -> Result<f64> {
        let value = self.number(cell, col, line)?;
        let column = &self.cells[col];
        if !value.is_finite() {
            return Err(CoreError::NonFinite {
                at: Location::Line(line),
                column: column.clone(),
                value,
                path: None,
            });
        }
        check_magnitude(value, t, column, Location::Line(line))?;
        Ok(value)
    }

    /// A cell as a number, its decimal mark checked against the file's.
    fn number(&mut self, cell: &str, col: usize, line: usize) -> Result<f64> {
        let column = &self.cells[col];
        let refuse = |reason: String| CoreError::DecimalMark {
            line,
            column: column.clone(),
            text: cell.to_owned(),
            reason,
            path: None,
        };
        let comma = cell.contains(',');
        let point = cell.contains('.');
        if comma && point {
            return Err(refuse(
                "a number with both `.` and `,` (thousands separators are not read)".to_owned(),
            ));
        }
        let text = match self.decimal {
            Decimal::Point { why } if comma => return Err(refuse(why.to_owned())),
            Decimal::Comma if point => {
                return Err(refuse(
                    "a `.` in a file declared to use decimal commas (a thousands separator?)"
                        .to_owned(),
                ));
            }
            Decimal::Detect(Some((mark, first)))
                if (mark == '.' && comma) || (mark == ',' && point) =>
            {
                return Err(refuse(format!(
                    "its decimal mark differs from the `{mark}` of the numbers from line {first}; \
                     declare the decimal mark (`--decimal-comma`, or none for `.`)"
                )));
            }
            Decimal::Detect(None) if comma || point => {
                self.decimal = Decimal::Detect(Some((if comma { ',' } else { '.' }, line)));
                cell.replacen(',', ".", 1)
            }
            _ if comma => cell.replacen(',', ".", 1),
            _ => cell.to_owned(),
        };
        text.parse().map_err(|_| CoreError::NotANumber {
            line,
            column: self.cells[col].clone(),
            text: cell.to_owned(),
            path: None,
        })
    }

    /// The recording, with its units and the notes on what was detected or left out.
    pub(super) fn finish(mut self, options: &CsvOptions) -> Result<CsvRecording> {
        if self.t.is_empty() {
            return Err(CoreError::EmptyRecording { path: None });
        }
        if let Some(index) = self.index.take()
            && index.broken_at.is_none()
        {
            let column = (!self.names[0].is_empty()).then_some(self.cells[0].as_str());
            self.notes.push(row_index_note(
                column,
                index.first.unwrap_or_default(),
                index.last.unwrap_or_default(),
            ));
            self.columns[0].clear();
            self.names[0].clear();
        }
        if let Some(unit) = &self.units[self.time]
            && self.time_per_second != 1.0
        {
            self.notes.push(format!(
                "time column `{}` read in {unit} and converted to seconds",
                self.cells[self.time]
            ));
        }
        let mut detected = Vec::new();
        if options.delimiter.is_none() && self.delimiter != b',' {
            detected.push(if self.delimiter == b'\t' {
                "tabs between cells".to_owned()
            } else {
                format!("`{}` between cells", char::from(self.delimiter))
            });
        }
        let decimal_comma = matches!(
            self.decimal,
            Decimal::Comma | Decimal::Detect(Some((',', _)))
        );
        if options.decimal_comma.is_none() && decimal_comma {
            detected.push("decimal commas".to_owned());
        }
        if !detected.is_empty() {
            self.notes
                .push(format!("read with {}", detected.join(" and ")));
        }
        let time_unit = self.units[self.time].clone();
        let time_column = self.cells[self.time].clone();
        let mut signals = Vec::new();
        let mut units = Vec::new();
        for (i, ((name, values), unit)) in self
            .names
            .into_iter()
            .zip(self.columns)
            .zip(self.units)
            .enumerate()
        {
            if i == self.time || (i == 0 && name.is_empty()) {
                continue;
            }
            signals.push(Signal::new(name, values));
            units.push(unit);
        }
        Ok(CsvRecording {
            recording: Recording::new(self.t, signals)?,
            time_column,
            time_unit,
            units,
            delimiter: self.delimiter,
            decimal_comma,
            notes: self.notes,
        })
    }
}

impl IndexColumn {
    /// Follows the row numbers: each a whole number, one more than the one before.
    fn follow(&mut self, cell: &str, line: usize) {
        if self.broken_at.is_some() {
            return;
        }
        match cell.parse::<f64>() {
            Ok(v) if next_row_number(self.last, v) => {
                self.first.get_or_insert(v);
                self.last = Some(v);
            }
            _ => self.broken_at = Some(line),
        }
    }
}
