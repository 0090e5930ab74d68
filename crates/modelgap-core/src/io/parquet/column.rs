//! One column of a Parquet file: what its numbers mean, from its types (and pandas'
//! metadata), and its values read over every row group.

use ::parquet::basic::{
    Compression, ConvertedType, Encoding, LogicalType, TimeUnit, Type as Physical,
};
use ::parquet::column::page::{Page, PageMetadata, PageReader};
use ::parquet::column::reader::{ColumnReader, ColumnReaderImpl, get_column_reader};
use ::parquet::data_type::DataType;
use ::parquet::errors::ParquetError;
use ::parquet::file::metadata::ParquetMetaData;
use ::parquet::file::reader::{FileReader, SerializedFileReader};
use ::parquet::schema::types::{ColumnDescPtr, ColumnDescriptor};
use bytes::Bytes;

use super::{Pandas, corrupt};
use crate::error::{CoreError, Location, Result};

/// Rows read from a column at a time.
const BATCH_ROWS: usize = 8192;

/// A unit of time a Parquet type counts in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Unit {
    Days,
    Millis,
    Micros,
    Nanos,
}

impl Unit {
    fn of(unit: &TimeUnit) -> Self {
        match unit {
            TimeUnit::MILLIS => Self::Millis,
            TimeUnit::MICROS => Self::Micros,
            TimeUnit::NANOS => Self::Nanos,
        }
    }

    /// `count` of this unit in seconds.
    pub(super) fn seconds(self, count: f64) -> f64 {
        match self {
            Self::Days => count * 86_400.0,
            Self::Millis => count / 1e3,
            Self::Micros => count / 1e6,
            Self::Nanos => count / 1e9,
        }
    }

    pub(super) fn name(self) -> &'static str {
        match self {
            Self::Days => "days",
            Self::Millis => "ms",
            Self::Micros => "us",
            Self::Nanos => "ns",
        }
    }
}

/// What a column's stored numbers mean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Kind {
    /// Numbers: floats, integers (`unsigned` ones read as such), decimals stored as integers
    /// scaled by `10^-scale`.
    Number { unsigned: bool, scale: i32 },
    /// Counts of `unit`; `instant` for a point in time (timestamps, dates), which the time
    /// column counts from its first sample; `what` names them in notes.
    Time {
        unit: Unit,
        instant: bool,
        what: &'static str,
    },
}

/// A column's values as stored: floats, or whole counts (integers, units of time).
pub(super) enum Stored {
    Floats(Vec<f64>),
    Counts(Vec<i64>),
}

/// One column of the file: its place, its name as written and what its numbers mean (or
/// what it holds instead of numbers).
pub(super) struct Column {
    /// Its place among the file's leaf columns.
    pub(super) index: usize,
    /// Its name as written (`u [V]`, `__index_level_0__`).
    pub(super) name: String,
    /// What its numbers mean; `Err` says what it holds instead (`text (BYTE_ARRAY, String)`).
    pub(super) kind: std::result::Result<Kind, String>,
    descr: ColumnDescPtr,
}

impl Column {
    /// The column `descr` at `index`, its kind read from its types and `pandas`.
    pub(super) fn new(index: usize, descr: ColumnDescPtr, pandas: &Pandas) -> Self {
        Self {
            index,
            name: descr.path().string(),
            kind: kind(&descr, pandas),
            descr,
        }
    }

    /// Reads the column over every row group; a null is refused with its row.
    pub(super) fn read(&self, reader: &SerializedFileReader<Bytes>) -> Result<Stored> {
        let metadata = reader.metadata();
        let unsigned = matches!(self.kind, Ok(Kind::Number { unsigned: true, .. }));
        let mut floats = Vec::new();
        let mut counts = Vec::new();
        let mut first_row = 0;
        for g in 0..metadata.num_row_groups() {
            let n = usize::try_from(metadata.row_group(g).num_rows()).map_err(|_| {
                CoreError::ParquetCorrupt {
                    reason: format!("row group {g} has a negative number of rows"),
                    path: None,
                }
            })?;
            let pages = reader
                .get_row_group(g)
                .and_then(|group| group.get_column_page_reader(self.index))
                .map_err(corrupt)?;
            let pages = Box::new(CheckedPages {
                inner: pages,
                dictionary: false,
            });
            let rows = Rows {
                first: first_row,
                n,
                column: &self.name,
                max_def: self.descr.max_def_level(),
            };
            match get_column_reader(self.descr.clone(), pages) {
                ColumnReader::DoubleColumnReader(r) => rows.read(r, &mut floats)?,
                ColumnReader::FloatColumnReader(r) => {
                    let mut v = Vec::new();
                    rows.read(r, &mut v)?;
                    floats.extend(v.into_iter().map(f64::from));
                }
                ColumnReader::Int32ColumnReader(r) => {
                    let mut v = Vec::new();
                    rows.read(r, &mut v)?;
                    // An unsigned 32-bit integer is stored in an i32's bits.
                    counts.extend(v.into_iter().map(|x| {
                        if unsigned {
                            i64::from(x as u32)
                        } else {
                            i64::from(x)
                        }
                    }));
                }
                ColumnReader::Int64ColumnReader(r) => rows.read(r, &mut counts)?,
                ColumnReader::Int96ColumnReader(r) => {
                    let mut v = Vec::new();
                    rows.read(r, &mut v)?;
                    counts.extend(v.iter().map(|x| x.to_nanos()));
                }
                // Refused by `kind` before any reading.
                _ => {
                    return Err(CoreError::ColumnType {
                        column: self.name.clone(),
                        found: format!("{:?} values", self.descr.physical_type()),
                        path: None,
                    });
                }
            }
            first_row += n;
        }
        Ok(match self.descr.physical_type() {
            Physical::FLOAT | Physical::DOUBLE => Stored::Floats(floats),
            _ => Stored::Counts(counts),
        })
    }

    /// The values as a signal holds them: numbers as they are (decimals scaled), timestamps
    /// and durations in seconds.
    pub(super) fn values(&self, stored: Stored) -> Vec<f64> {
        match (stored, self.kind.as_ref().ok().copied()) {
            (Stored::Floats(v), _) => v,
            (Stored::Counts(v), Some(Kind::Time { unit, .. })) => {
                v.into_iter().map(|c| unit.seconds(c as f64)).collect()
            }
            (Stored::Counts(v), Some(Kind::Number { unsigned, scale })) => {
                let divisor = 10f64.powi(scale);
                v.into_iter()
                    .map(|c| {
                        // An unsigned 64-bit integer is stored in an i64's bits.
                        let x = if unsigned { c as u64 as f64 } else { c as f64 };
                        if scale == 0 { x } else { x / divisor }
                    })
                    .collect()
            }
            (Stored::Counts(v), None) => v.into_iter().map(|c| c as f64).collect(),
        }
    }
}

/// What a column's numbers mean, from its physical and logical types (and pandas' metadata
/// for durations); `Err` says what it holds instead.
fn kind(descr: &ColumnDescriptor, pandas: &Pandas) -> std::result::Result<Kind, String> {
    let physical = descr.physical_type();
    if descr.max_rep_level() > 0 || descr.path().parts().len() > 1 {
        return Err("nested values (a list, struct or map)".to_owned());
    }
    let number = Kind::Number {
        unsigned: false,
        scale: 0,
    };
    let logical = descr.logical_type_ref();
    let refuse = |what: &str| Err(format!("{what} ({physical:?}{})", describe(logical)));
    match physical {
        Physical::FLOAT | Physical::DOUBLE => return Ok(number),
        Physical::INT96 => {
            return Ok(Kind::Time {
                unit: Unit::Nanos,
                instant: true,
                what: "timestamps",
            });
        }
        Physical::BOOLEAN => return refuse("booleans"),
        Physical::BYTE_ARRAY => {
            return match logical {
                Some(LogicalType::String | LogicalType::Enum | LogicalType::Json) => refuse("text"),
                _ if descr.converted_type() == ConvertedType::UTF8 => refuse("text"),
                _ => refuse("bytes"),
            };
        }
        Physical::FIXED_LEN_BYTE_ARRAY => {
            return match logical {
                Some(LogicalType::Float16) => refuse("16-bit floats"),
                _ => refuse("fixed-length bytes"),
            };
        }
        Physical::INT32 | Physical::INT64 => {}
    }
    let timestamp = |unit, instant, what| {
        Ok(Kind::Time {
            unit,
            instant,
            what,
        })
    };
    match logical {
        Some(LogicalType::Integer(int)) => Ok(Kind::Number {
            unsigned: !int.is_signed,
            scale: 0,
        }),
        Some(LogicalType::Decimal(decimal)) => Ok(Kind::Number {
            unsigned: false,
            scale: decimal.scale,
        }),
        Some(LogicalType::Timestamp(ts)) => timestamp(Unit::of(&ts.unit), true, "timestamps"),
        Some(LogicalType::Time(tt)) => timestamp(Unit::of(&tt.unit), false, "times of day"),
        Some(LogicalType::Date) => timestamp(Unit::Days, true, "dates"),
        Some(_) => refuse("values"),
        None => match descr.converted_type() {
            ConvertedType::UINT_8
            | ConvertedType::UINT_16
            | ConvertedType::UINT_32
            | ConvertedType::UINT_64 => Ok(Kind::Number {
                unsigned: true,
                scale: 0,
            }),
            ConvertedType::DECIMAL => Ok(Kind::Number {
                unsigned: false,
                scale: descr.type_scale(),
            }),
            ConvertedType::TIMESTAMP_MILLIS => timestamp(Unit::Millis, true, "timestamps"),
            ConvertedType::TIMESTAMP_MICROS => timestamp(Unit::Micros, true, "timestamps"),
            ConvertedType::TIME_MILLIS => timestamp(Unit::Millis, false, "times of day"),
            ConvertedType::TIME_MICROS => timestamp(Unit::Micros, false, "times of day"),
            ConvertedType::DATE => timestamp(Unit::Days, true, "dates"),
            ConvertedType::NONE
            | ConvertedType::INT_8
            | ConvertedType::INT_16
            | ConvertedType::INT_32
            | ConvertedType::INT_64 => {
                match pandas.durations.iter().find(|(n, _)| n == descr.name()) {
                    Some(&(_, unit)) => timestamp(unit, false, "durations"),
                    None => Ok(number),
                }
            }
            other => refuse(&format!("values of converted type {other}")),
        },
    }
}

/// `, <logical type>` when there is one, for messages.
fn describe(logical: Option<&LogicalType>) -> String {
    match logical {
        Some(LogicalType::String) => ", String".to_owned(),
        Some(l) => format!(", {l:?}"),
        None => String::new(),
    }
}

/// Checks the column chunks to be read before reading them: their codec one the crate is
/// built with (gzip, brotli, lz4 and lzo are refused, naming the column), their place in the
/// file not negative (the parquet crate asserts it).
pub(super) fn check_chunks<'a>(
    metadata: &ParquetMetaData,
    columns: &[Column],
    read: impl Iterator<Item = &'a usize> + Clone,
) -> Result<()> {
    for (g, group) in metadata.row_groups().iter().enumerate() {
        for &i in read.clone() {
            let Some(chunk) = group.columns().get(i) else {
                return Err(CoreError::ParquetCorrupt {
                    reason: format!(
                        "row group {g} has {} columns, the schema {}",
                        group.columns().len(),
                        columns.len()
                    ),
                    path: None,
                });
            };
            if chunk.data_page_offset() < 0
                || chunk.dictionary_page_offset().is_some_and(|o| o < 0)
                || chunk.compressed_size() < 0
            {
                return Err(CoreError::ParquetCorrupt {
                    reason: format!(
                        "column `{}` of row group {g} has a negative offset or size",
                        columns[i].name
                    ),
                    path: None,
                });
            }
            let codec = match chunk.compression() {
                Compression::UNCOMPRESSED | Compression::SNAPPY | Compression::ZSTD(_) => continue,
                Compression::GZIP(_) => "gzip",
                Compression::BROTLI(_) => "brotli",
                Compression::LZ4 | Compression::LZ4_RAW => "lz4",
                Compression::LZO => "lzo",
            };
            return Err(CoreError::ParquetCodec {
                column: columns[i].name.clone(),
                codec: codec.to_owned(),
                path: None,
            });
        }
    }
    Ok(())
}

impl Stored {
    pub(super) fn len(&self) -> usize {
        match self {
            Self::Floats(v) => v.len(),
            Self::Counts(v) => v.len(),
        }
    }
}

/// The rows of one row group of one column.
struct Rows<'a> {
    /// The group's first row in the file.
    first: usize,
    /// Its number of rows.
    n: usize,
    column: &'a str,
    /// The definition level of a value that is there (0 for a column without nulls).
    max_def: i16,
}

impl Rows<'_> {
    /// Reads the group's values into `out`; a null is refused with its row.
    fn read<T: DataType>(
        &self,
        mut reader: ColumnReaderImpl<T>,
        out: &mut Vec<T::T>,
    ) -> Result<()> {
        let mut levels = Vec::new();
        let mut done = 0;
        while done < self.n {
            levels.clear();
            let def = (self.max_def > 0).then_some(&mut levels);
            let (rows, values, _) = reader
                .read_records((self.n - done).min(BATCH_ROWS), def, None, out)
                .map_err(corrupt)?;
            if rows == 0 {
                break;
            }
            if values < rows {
                let k = levels
                    .iter()
                    .position(|&d| d < self.max_def)
                    .unwrap_or_default();
                return Err(CoreError::MissingValue {
                    at: Location::Row(self.first + done + k),
                    column: self.column.to_owned(),
                    path: None,
                });
            }
            done += rows;
        }
        if done != self.n {
            return Err(CoreError::ParquetCorrupt {
                reason: format!(
                    "column `{}` has {done} values in the row group from row {}, which has {} rows",
                    self.column, self.first, self.n
                ),
                path: None,
            });
        }
        Ok(())
    }
}

/// A column chunk's pages, a dictionary-encoded data page refused unless a dictionary page
/// came first (the parquet crate's decoder panics on one in a damaged file).
struct CheckedPages {
    inner: Box<dyn PageReader>,
    /// Whether a dictionary page has been read.
    dictionary: bool,
}

impl PageReader for CheckedPages {
    fn get_next_page(&mut self) -> ::parquet::errors::Result<Option<Page>> {
        let page = self.inner.get_next_page()?;
        match &page {
            Some(Page::DictionaryPage { .. }) => self.dictionary = true,
            Some(page)
                if !self.dictionary
                    && matches!(
                        page.encoding(),
                        Encoding::PLAIN_DICTIONARY | Encoding::RLE_DICTIONARY
                    ) =>
            {
                return Err(ParquetError::General(
                    "a dictionary-encoded data page comes before any dictionary page".to_owned(),
                ));
            }
            _ => {}
        }
        Ok(page)
    }

    fn peek_next_page(&mut self) -> ::parquet::errors::Result<Option<PageMetadata>> {
        self.inner.peek_next_page()
    }

    fn skip_next_page(&mut self) -> ::parquet::errors::Result<()> {
        self.inner.skip_next_page()
    }
}

impl Iterator for CheckedPages {
    type Item = ::parquet::errors::Result<Page>;

    fn next(&mut self) -> Option<Self::Item> {
        self.get_next_page().transpose()
    }
}
