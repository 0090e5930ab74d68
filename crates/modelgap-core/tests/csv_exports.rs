//! Recordings as other tools export them (issue 16, item 3): pandas `to_csv`, R
//! `write.csv`, a spreadsheet's `;` and decimal commas, units in the header or a unit row, the
//! time column anywhere or named by an option; and each refusal, typed, with its line.

use modelgap_core::CoreError;
use modelgap_core::error::Location;
use modelgap_core::io::csv::{CsvOptions, CsvRecording, read_signals, read_signals_with};

fn read(text: &str) -> CsvRecording {
    read_with(text, &CsvOptions::default())
}

fn read_with(text: &str, options: &CsvOptions) -> CsvRecording {
    match read_signals_with(text.as_bytes(), options) {
        Ok(read) => read,
        Err(e) => panic!("{e}\n--- text ---\n{text}"),
    }
}

fn refuse(text: &str) -> CoreError {
    refuse_with(text, &CsvOptions::default())
}

fn refuse_with(text: &str, options: &CsvOptions) -> CoreError {
    match read_signals_with(text.as_bytes(), options) {
        Ok(read) => panic!("expected an error, read {:?}", read.recording),
        Err(e) => e,
    }
}

/// What the three exports below hold: `t`, `u`, `y` over three samples.
fn assert_tuy(read: &CsvRecording) {
    let rec = &read.recording;
    assert_eq!(rec.t(), &[0.0, 0.001, 0.002]);
    assert_eq!(rec.names(), vec!["u", "y"]);
    assert_eq!(rec.values("u").ok(), Some(&[1.0, 1.0, 1.5][..]));
    assert_eq!(rec.values("y").ok(), Some(&[0.5, 0.5012, 0.5024][..]));
}

#[test]
fn pandas_to_csv_index_column_is_left_out_with_a_note() {
    // `pd.DataFrame({"t": …, "u": …, "y": …}).to_csv("run.csv")`
    let read = read(",t,u,y\n0,0.0,1.0,0.5\n1,0.001,1.0,0.5012\n2,0.002,1.5,0.5024\n");
    assert_tuy(&read);
    assert_eq!(read.time_column, "t");
    assert_eq!(
        read.notes,
        vec![
            "the first column (unnamed) holds the row numbers 0 to 2: read as a row index and \
             left out"
        ]
    );
}

#[test]
fn pandas_exports_read_as_pandas_writes_them() {
    // Verbatim from pandas 2 (`df.to_csv(...)` on a frame with columns `t`, `u [V]`, `y`).
    let t = [0.0, 0.001, 0.002, 0.003, 0.004];
    let u = [1.0, 1.0, 1.5, 1e-5, 2.0];
    let y = [0.5, 0.25, 1.0 / 3.0, 2.0, 1e-7];
    let default = ",t,u [V],y\n0,0.0,1.0,0.5\n1,0.001,1.0,0.25\n2,0.002,1.5,0.3333333333333333\n\
                   3,0.003,1e-05,2.0\n4,0.004,2.0,1e-07\n";
    // `sep=";", decimal=",", index=False`
    let german = "t;u [V];y\n0,0;1,0;0,5\n0,001;1,0;0,25\n0,002;1,5;0,3333333333333333\n\
                  0,003;1e-05;2,0\n0,004;2,0;1e-07\n";
    // `decimal=","` with the default `,`: the numbers quoted.
    let quoted = ",t,u [V],y\n0,\"0,0\",\"1,0\",\"0,5\"\n1,\"0,001\",\"1,0\",\"0,25\"\n\
                  2,\"0,002\",\"1,5\",\"0,3333333333333333\"\n3,\"0,003\",1e-05,\"2,0\"\n\
                  4,\"0,004\",\"2,0\",1e-07\n";
    for (name, text, options) in [
        ("default", default, CsvOptions::default()),
        ("german", german, CsvOptions::default()),
        ("quoted", quoted, CsvOptions::default().decimal_comma(true)),
    ] {
        let read = read_with(text, &options);
        let rec = &read.recording;
        assert_eq!(rec.t(), &t, "{name}");
        assert_eq!(rec.values("u").ok(), Some(&u[..]), "{name}");
        assert_eq!(rec.values("y").ok(), Some(&y[..]), "{name}");
        assert_eq!(read.unit("u"), Some("V"), "{name}");
    }
    // Without the declaration, the quoted decimal commas are refused.
    let e = refuse(quoted);
    assert!(matches!(e, CoreError::DecimalMark { line: 2, .. }), "{e}");
    // `df.reset_index().to_csv()`: the unnamed row index is left out, `index` kept.
    let reset = ",index,t,u [V],y\n0,0,0.0,1.0,0.5\n1,1,0.001,1.0,0.25\n";
    let read = read(reset);
    assert_eq!(read.recording.names(), vec!["index", "u", "y"]);
}

#[test]
fn pandas_index_named_or_written_back_is_left_out() {
    for first in ["index", "Unnamed: 0"] {
        let read = read(&format!(
            "{first},t,u,y\n10,0.0,1.0,0.5\n11,0.001,1.0,0.5012\n12,0.002,1.5,0.5024\n"
        ));
        assert_tuy(&read);
        assert!(
            read.notes[0].contains(&format!("`{first}`")),
            "{:?}",
            read.notes
        );
    }
}

#[test]
fn r_write_csv_quoted_header_and_row_names_are_read() {
    // `write.csv(data.frame(t = …, u = …, y = …), "run.csv")`
    let read = read(
        "\"\",\"t\",\"u\",\"y\"\n\"1\",0,1,0.5\n\"2\",0.001,1,0.5012\n\"3\",0.002,1.5,0.5024\n",
    );
    assert_tuy(&read);
    assert!(
        read.notes[0].contains("row numbers 1 to 3"),
        "{:?}",
        read.notes
    );
}

#[test]
fn spreadsheet_semicolons_decimal_commas_units_bom_and_crlf_are_read() {
    // A spreadsheet's "CSV UTF-8" in a locale that writes 0,5: BOM, `;`, CRLF.
    let text = "\u{feff}Time [s];u [V];y (A)\r\n0;1;0,5\r\n0,001;1;0,5012\r\n0,002;1,5;0,5024\r\n";
    let read = read(text);
    assert_tuy(&read);
    assert_eq!(read.time_column, "Time [s]");
    assert_eq!(read.time_unit.as_deref(), Some("s"));
    assert_eq!(read.unit("u"), Some("V"));
    assert_eq!(read.unit("y"), Some("A"));
    assert_eq!(read.delimiter, b';');
    assert!(read.decimal_comma);
    assert_eq!(
        read.notes,
        vec!["read with `;` between cells and decimal commas"]
    );
}

#[test]
fn tabs_separate_cells_when_the_header_has_no_comma() {
    let read = read("t\tu\ty\n0\t1\t0,5\n0,001\t1\t0,5012\n0,002\t1,5\t0,5024\n");
    assert_tuy(&read);
    assert_eq!(read.delimiter, b'\t');
}

#[test]
fn semicolon_file_with_decimal_points_reads() {
    let read = read("t;u;y\n0;1;0.5\n0.001;1;0.5012\n0.002;1.5;0.5024\n");
    assert_tuy(&read);
    assert!(!read.decimal_comma);
}

#[test]
fn declared_delimiter_and_decimal_comma_read_a_quoted_pandas_export() {
    // `df.to_csv(decimal=",")` keeps `,` between cells and quotes the numbers.
    let text = ",t,u,y\n0,0,1,\"0,5\"\n1,\"0,001\",1,\"0,5012\"\n2,\"0,002\",\"1,5\",\"0,5024\"\n";
    let read = read_with(text, &CsvOptions::default().decimal_comma(true));
    assert_tuy(&read);
    let semicolons = "t;u;y\n0;1;0,5\n0,001;1;0,5012\n0,002;1,5;0,5024\n";
    let read = read_with(
        semicolons,
        &CsvOptions::default().delimiter(b';').decimal_comma(true),
    );
    assert_tuy(&read);
    assert!(read.notes.is_empty(), "nothing detected: {:?}", read.notes);
}

#[test]
fn time_column_may_stand_anywhere() {
    let read = read("u,y,t\n1.0,0.5,0\n1.0,0.5012,0.001\n1.5,0.5024,0.002\n");
    assert_tuy(&read);
}

#[test]
fn time_column_named_time_in_any_case_with_a_unit() {
    for name in ["time", "Time", "TIME [s]", "T", "t [s]", "time(s)"] {
        let text = format!("u,{name},y\n1.0,0,0.5\n1.0,0.001,0.5012\n1.5,0.002,0.5024\n");
        let rec = read_signals_with(text.as_bytes(), &CsvOptions::default());
        // `time(s)` has no space before the parenthesis: a name, not a unit.
        if name == "time(s)" {
            assert!(
                matches!(rec, Err(CoreError::MissingTimeColumn { .. })),
                "{name}"
            );
        } else {
            assert_tuy(&rec.unwrap());
        }
    }
}

#[test]
fn time_column_chosen_by_option_with_or_without_its_unit() {
    let text = "stamp [s],u,y\n0,1.0,0.5\n0.001,1.0,0.5012\n0.002,1.5,0.5024\n";
    for name in ["stamp", "stamp [s]"] {
        let read = read_with(text, &CsvOptions::default().time(name));
        assert_tuy(&read);
        assert_eq!(read.time_column, "stamp [s]");
    }
    // An unnamed first column can be chosen as time by its empty name.
    let read = read_with(
        ",u,y\n0,1.0,0.5\n0.001,1.0,0.5012\n0.002,1.5,0.5024\n",
        &CsvOptions::default().time(""),
    );
    assert_tuy(&read);
}

#[test]
fn time_in_milliseconds_is_converted_to_seconds() {
    let read = read("time [ms],u,y\n0,1.0,0.5\n1,1.0,0.5012\n2,1.5,0.5024\n");
    assert_tuy(&read);
    assert_eq!(read.time_unit.as_deref(), Some("ms"));
    assert_eq!(
        read.notes,
        vec!["time column `time [ms]` read in ms and converted to seconds"]
    );
}

#[test]
fn header_units_in_brackets_or_parentheses() {
    let read = read("t [s],u[V],y (rad/s)\n0,1.0,0.5\n0.001,1.0,0.5012\n0.002,1.5,0.5024\n");
    assert_tuy(&read);
    assert_eq!(
        read.units,
        vec![Some("V".to_owned()), Some("rad/s".to_owned())]
    );
}

#[test]
fn unit_row_under_the_header_gives_the_units() {
    let units = read("t,u,y\ns,[V],\n0,1.0,0.5\n0.001,1.0,0.5012\n0.002,1.5,0.5024\n");
    assert_tuy(&units);
    assert_eq!(units.time_unit.as_deref(), Some("s"));
    assert_eq!(units.units, vec![Some("V".to_owned()), None]);
    assert_eq!(units.notes, vec!["line 2 read as the columns' units"]);
    // A unit row in ms converts time as a header unit does.
    let ms = read(",t,u,y\n,ms,V,A\n0,0,1.0,0.5\n1,1,1.0,0.5012\n2,2,1.5,0.5024\n");
    assert_tuy(&ms);
    assert_eq!(ms.units, vec![Some("V".to_owned()), Some("A".to_owned())]);
    assert_eq!(ms.notes.len(), 3, "{:?}", ms.notes);
}

#[test]
fn quoted_cells_may_hold_commas_and_quotes() {
    let read = read("t,\"speed, measured\",\"the \"\"y\"\"\"\n0,1,2\n");
    assert_eq!(read.recording.names(), vec!["speed, measured", "the \"y\""]);
}

#[test]
fn read_signals_is_read_signals_with_defaults() {
    let text = ",t,u,y\n0,0.0,1.0,0.5\n1,0.001,1.0,0.5012\n2,0.002,1.5,0.5024\n";
    assert_eq!(read_signals(text.as_bytes()).unwrap(), read(text).recording);
}

// --- refusals ---------------------------------------------------------------------------

#[test]
fn decimal_comma_with_comma_between_cells_is_refused_never_split() {
    // Quoted, the cell is whole: refused unless declared.
    let e = refuse("t,u\n0,\"1,5\"\n");
    assert!(
        matches!(e, CoreError::DecimalMark { line: 2, ref column, ref text, .. }
            if column == "u" && text == "1,5"),
        "{e}"
    );
    assert!(e.to_string().contains("declare decimal commas"), "{e}");
    // Unquoted, the row has a cell too many.
    let e = refuse("t,u\n0,1,5\n");
    assert!(
        matches!(
            e,
            CoreError::RowLength {
                line: 2,
                expected: 2,
                found: 3,
                ..
            }
        ),
        "{e}"
    );
    // Declared off, a comma is refused even with `;` between cells.
    let e = refuse_with("t;u\n0;1,5\n", &CsvOptions::default().decimal_comma(false));
    assert!(matches!(e, CoreError::DecimalMark { line: 2, .. }), "{e}");
}

#[test]
fn mixed_or_double_decimal_marks_are_refused_with_the_line() {
    let e = refuse("t;u\n0;1,5\n1;2.5\n");
    assert!(matches!(e, CoreError::DecimalMark { line: 3, .. }), "{e}");
    assert!(e.to_string().contains("from line 2"), "{e}");
    let e = refuse("t;u\n0;1.234,5\n");
    assert!(matches!(e, CoreError::DecimalMark { line: 2, .. }), "{e}");
    let e = refuse_with("t;u\n0;1.5\n", &CsvOptions::default().decimal_comma(true));
    assert!(matches!(e, CoreError::DecimalMark { line: 2, .. }), "{e}");
}

#[test]
fn missing_time_column_lists_the_columns_and_how_to_choose() {
    let e = refuse("# run 3\nstamp,u,y\n0,1,2\n");
    assert_eq!(
        e.to_string(),
        "missing column `t`: the header at line 2 has no column `t` or `time` (with or \
         without a unit); its columns are `stamp`, `u`, `y`: choose the time column with the \
         time option (`--time COL`)"
    );
    let e = refuse_with("t,u\n0,1\n", &CsvOptions::default().time("stamp"));
    assert!(
        matches!(e, CoreError::MissingTimeColumn { line: Some(1), asked: Some(ref a), ref columns, .. }
            if a == "stamp" && columns == &["t", "u"]),
        "{e}"
    );
    assert!(e.to_string().starts_with("missing column `stamp`"), "{e}");
}

#[test]
fn two_time_like_columns_are_refused_unless_one_is_t() {
    let e = refuse("time,T [s],u\n0,0,1\n");
    assert!(
        matches!(e, CoreError::AmbiguousTimeColumn { line: Some(1), ref columns, .. }
            if columns == &["time", "T [s]"]),
        "{e}"
    );
    // A column named exactly `t` is time; `time` beside it is a signal.
    let read = read("time,t\n5,0\n6,1\n");
    assert_eq!(read.recording.values("time").unwrap(), &[5.0, 6.0]);
}

#[test]
fn unknown_time_unit_is_refused() {
    let e = refuse("time [min],u\n0,1\n");
    assert!(
        matches!(e, CoreError::TimeUnit { line: Some(1), ref unit, .. } if unit == "min"),
        "{e}"
    );
}

#[test]
fn index_column_that_is_not_a_row_index_is_kept_as_a_signal() {
    let read = read("index,t,u\n0,0,1\n2,1,2\n3,2,3\n");
    assert_eq!(read.recording.names(), vec!["index", "u"]);
    assert_eq!(read.recording.values("index").unwrap(), &[0.0, 2.0, 3.0]);
    assert!(read.notes.is_empty());
    // Named and kept, its cells must be numbers like any signal's.
    let e = refuse("index,t,u\n0,0,1\nx,1,2\n");
    assert!(
        matches!(e, CoreError::NotANumber { line: 3, ref column, .. } if column == "index"),
        "{e}"
    );
}

#[test]
fn unnamed_column_that_is_not_a_row_index_is_refused_at_its_line() {
    let e = refuse(",t,u\n0,0,1\n1,1,2\n1.5,2,3\n");
    assert!(
        matches!(e, CoreError::InvalidSignalName { at: Some(Location::Line(4)), ref name, .. }
            if name.is_empty()),
        "{e}"
    );
    let e = refuse("\"\",\"t\",\"u\"\n\"a\",0,1\n");
    assert!(
        matches!(
            e,
            CoreError::InvalidSignalName {
                at: Some(Location::Line(2)),
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn quoted_cell_spanning_lines_is_refused_at_its_line() {
    let e = refuse("t,\"u\nv\"\n0,1\n");
    assert!(
        matches!(
            e,
            CoreError::CsvQuoting {
                line: 1,
                cell: 2,
                ..
            }
        ),
        "{e}"
    );
    // A quote never closed runs to the end of the file.
    let e = refuse("t,u\n\n0,1\n1,\"2\n2,3\n");
    assert!(
        matches!(
            e,
            CoreError::CsvQuoting {
                line: 4,
                cell: 2,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("missing closing quote"), "{e}");
}

#[test]
fn bad_quoting_is_refused_with_line_and_cell() {
    for (text, line, cell) in [
        ("t,u\n0,1\"2\n", 2, 2),           // a quote inside an unquoted cell
        ("t,u\r\n\r\n0,\"1\"2\r\n", 3, 2), // text after the closing quote
        ("t,u\n0, \"1\"\n", 2, 2),         // a quote after spaces
        ("t,\"u\n", 1, 2),                 // never closed, last line
        ("\"t\",\"u\n", 1, 2),             // the same, from the header
    ] {
        let e = refuse(text);
        assert!(
            matches!(e, CoreError::CsvQuoting { line: l, cell: c, .. } if l == line && c == cell),
            "{text:?}: {e}"
        );
    }
}

#[test]
fn line_numbers_hold_after_blank_lines_comments_and_crlf() {
    let e = refuse("# c\r\n\r\n,t,u\r\n0,0,1\r\n\r\n# c\r\n1,1,x\r\n");
    assert!(
        matches!(e, CoreError::NotANumber { line: 7, ref column, .. } if column == "u"),
        "{e}"
    );
}

#[test]
fn declared_delimiter_that_cannot_separate_cells_is_refused() {
    for d in [b'"', b'\n', b'1', b'.'] {
        let e = refuse_with("t,u\n0,1\n", &CsvOptions::default().delimiter(d));
        assert!(
            matches!(
                e,
                CoreError::InvalidArgument {
                    name: "delimiter",
                    ..
                }
            ),
            "{e}"
        );
    }
}
