//! A sweep's results as a table of typed columns, written and read back as CSV or as Apache
//! Parquet. Writing depends on nothing but the table: the same table gives the same bytes,
//! which is what lets `lsdc sweep gather` rebuild the unsharded file bit for bit.
//!
//! CSV: a header of the columns' names, a row per line; numbers in Rust's shortest exponent form
//! (`1.5e0`, which reads back to the same bits), an empty field for a missing value, texts
//! quoted as RFC 4180 says when they hold a comma, a quote or a line break.
//!
//! Parquet: one row group, no compression (the crate is built without codecs), the columns as
//! `Kind` says: `INT64` for indices and counts, `DOUBLE` for numbers, `BYTE_ARRAY` (UTF-8) for
//! texts; optional unless the kind is required. Written and read with the `parquet` crate's own
//! column writers and record reader, without its `arrow` layer.

use std::fmt::Write as _;
use std::fs::File;
use std::path::Path;
use std::sync::Arc;

use parquet::basic::{ConvertedType, Repetition, Type as PhysicalType};
use parquet::data_type::{ByteArray, ByteArrayType, DoubleType, Int64Type};
use parquet::file::properties::WriterProperties;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::SerializedFileWriter;
use parquet::record::Field;
use parquet::schema::types::Type as SchemaType;

/// What a column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A run's index: an integer in every row.
    Index,
    /// An integer, or nothing.
    Count,
    /// A word in every row (`ok`).
    Label,
    /// A text, or nothing.
    Text,
    /// A number, or nothing.
    Number,
}

impl Kind {
    fn required(self) -> bool {
        matches!(self, Kind::Index | Kind::Label)
    }
}

/// A column's cells.
#[derive(Clone, Debug, PartialEq)]
pub enum Cells {
    Integers(Vec<Option<i64>>),
    Texts(Vec<Option<String>>),
    Numbers(Vec<Option<f64>>),
}

impl Cells {
    fn len(&self) -> usize {
        match self {
            Cells::Integers(c) => c.len(),
            Cells::Texts(c) => c.len(),
            Cells::Numbers(c) => c.len(),
        }
    }

    fn empty(kind: Kind) -> Cells {
        match kind {
            Kind::Index | Kind::Count => Cells::Integers(Vec::new()),
            Kind::Label | Kind::Text => Cells::Texts(Vec::new()),
            Kind::Number => Cells::Numbers(Vec::new()),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Column {
    pub name: String,
    pub kind: Kind,
    pub cells: Cells,
}

impl Column {
    pub fn integers(name: String, kind: Kind, cells: Vec<Option<i64>>) -> Column {
        Column {
            name,
            kind,
            cells: Cells::Integers(cells),
        }
    }

    pub fn texts(name: String, kind: Kind, cells: Vec<Option<String>>) -> Column {
        Column {
            name,
            kind,
            cells: Cells::Texts(cells),
        }
    }

    pub fn numbers(name: String, cells: Vec<Option<f64>>) -> Column {
        Column {
            name,
            kind: Kind::Number,
            cells: Cells::Numbers(cells),
        }
    }
}

/// Columns of equal length.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub columns: Vec<Column>,
}

/// The formats of a table's file, by its extension: `.parquet`, else CSV.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableFormat {
    Csv,
    Parquet,
}

impl TableFormat {
    pub fn of(path: &Path) -> TableFormat {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("parquet") => TableFormat::Parquet,
            _ => TableFormat::Csv,
        }
    }
}

impl Table {
    pub fn row_count(&self) -> usize {
        self.columns.first().map_or(0, |c| c.cells.len())
    }

    pub fn names(&self) -> Vec<&str> {
        self.columns.iter().map(|c| c.name.as_str()).collect()
    }

    /// The `run` column (the first), each row's run index.
    pub fn runs(&self) -> Vec<i64> {
        match self.columns.first().map(|c| &c.cells) {
            Some(Cells::Integers(cells)) => cells.iter().map(|c| c.unwrap_or(-1)).collect(),
            _ => Vec::new(),
        }
    }

    /// The rows of `self` in the order of `order` (indices of rows).
    pub fn reordered(&self, order: &[usize]) -> Table {
        fn pick<T: Clone>(cells: &[T], order: &[usize]) -> Vec<T> {
            order.iter().map(|&i| cells[i].clone()).collect()
        }
        let columns = (self.columns.iter())
            .map(|c| Column {
                name: c.name.clone(),
                kind: c.kind,
                cells: match &c.cells {
                    Cells::Integers(v) => Cells::Integers(pick(v, order)),
                    Cells::Texts(v) => Cells::Texts(pick(v, order)),
                    Cells::Numbers(v) => Cells::Numbers(pick(v, order)),
                },
            })
            .collect();
        Table { columns }
    }

    /// The rows of `other` after those of `self`; the columns must be the same.
    pub fn append(&mut self, other: Table) -> Result<(), String> {
        if self.names() != other.names() {
            return Err("their columns differ".to_string());
        }
        for (mine, theirs) in self.columns.iter_mut().zip(other.columns) {
            match (&mut mine.cells, theirs.cells) {
                (Cells::Integers(a), Cells::Integers(b)) => a.extend(b),
                (Cells::Texts(a), Cells::Texts(b)) => a.extend(b),
                (Cells::Numbers(a), Cells::Numbers(b)) => a.extend(b),
                _ => return Err(format!("the column `{}` has another type", mine.name)),
            }
        }
        Ok(())
    }

    /// The table as CSV text.
    pub fn to_csv(&self) -> String {
        let mut out = String::new();
        let header: Vec<String> = self.columns.iter().map(|c| quoted(&c.name)).collect();
        out.push_str(&header.join(","));
        out.push('\n');
        for row in 0..self.row_count() {
            for (k, column) in self.columns.iter().enumerate() {
                if k > 0 {
                    out.push(',');
                }
                match &column.cells {
                    Cells::Integers(v) => {
                        if let Some(x) = v[row] {
                            let _ = write!(out, "{x}");
                        }
                    }
                    Cells::Texts(v) => {
                        if let Some(text) = &v[row] {
                            out.push_str(&quoted(text));
                        }
                    }
                    Cells::Numbers(v) => {
                        if let Some(x) = v[row] {
                            let _ = write!(out, "{x:e}");
                        }
                    }
                }
            }
            out.push('\n');
        }
        out
    }

    /// Reads a table from CSV text, each column's type given by its name.
    pub fn from_csv(text: &str, kind_of: fn(&str) -> Kind) -> Result<Table, String> {
        let mut records = csv_records(text)?.into_iter();
        let header = records.next().ok_or("no header")?;
        let mut columns: Vec<Column> = (header.into_iter())
            .map(|name| Column {
                kind: kind_of(&name),
                cells: Cells::empty(kind_of(&name)),
                name,
            })
            .collect();
        for (row, fields) in records.enumerate() {
            let line = row + 2;
            if fields.len() != columns.len() {
                return Err(format!(
                    "line {line}: {} fields for {} columns",
                    fields.len(),
                    columns.len()
                ));
            }
            for (column, field) in columns.iter_mut().zip(fields) {
                let missing = field.is_empty() && column.kind != Kind::Text;
                let bad = |what: &str| {
                    format!(
                        "line {line}, column `{}`: `{field}` is not {what}",
                        column.name
                    )
                };
                match &mut column.cells {
                    Cells::Integers(v) if missing => v.push(None),
                    Cells::Integers(v) => {
                        v.push(Some(field.parse().map_err(|_| bad("an integer"))?))
                    }
                    Cells::Numbers(v) if missing => v.push(None),
                    Cells::Numbers(v) => v.push(Some(field.parse().map_err(|_| bad("a number"))?)),
                    Cells::Texts(v) if field.is_empty() => v.push(None),
                    Cells::Texts(v) => v.push(Some(field)),
                }
            }
        }
        Ok(Table { columns })
    }

    /// Writes the table as a Parquet file.
    pub fn write_parquet(&self, path: &Path) -> Result<(), String> {
        let error = |e: parquet::errors::ParquetError| e.to_string();
        let fields = (self.columns.iter())
            .map(|c| {
                let (physical, converted) = match c.kind {
                    Kind::Index | Kind::Count => (PhysicalType::INT64, ConvertedType::NONE),
                    Kind::Label | Kind::Text => (PhysicalType::BYTE_ARRAY, ConvertedType::UTF8),
                    Kind::Number => (PhysicalType::DOUBLE, ConvertedType::NONE),
                };
                let repetition = match c.kind.required() {
                    true => Repetition::REQUIRED,
                    false => Repetition::OPTIONAL,
                };
                SchemaType::primitive_type_builder(&c.name, physical)
                    .with_repetition(repetition)
                    .with_converted_type(converted)
                    .build()
                    .map(Arc::new)
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(error)?;
        let schema = SchemaType::group_type_builder("sweep")
            .with_fields(fields)
            .build()
            .map_err(error)?;
        let file = File::create(path).map_err(|e| e.to_string())?;
        let properties = Arc::new(WriterProperties::builder().build());
        let mut writer =
            SerializedFileWriter::new(file, Arc::new(schema), properties).map_err(error)?;
        let mut group = writer.next_row_group().map_err(error)?;
        let mut columns = self.columns.iter();
        while let Some(mut column_writer) = group.next_column().map_err(error)? {
            let column = columns
                .next()
                .ok_or("more columns in the schema than in the table")?;
            // Definition levels: 1 where a value is, 0 where it is missing.
            let levels =
                |present: Vec<bool>| present.into_iter().map(i16::from).collect::<Vec<i16>>();
            match &column.cells {
                Cells::Integers(v) => {
                    let values: Vec<i64> = v.iter().flatten().copied().collect();
                    let defined = levels(v.iter().map(Option::is_some).collect());
                    (column_writer.typed::<Int64Type>())
                        .write_batch(&values, Some(&defined), None)
                        .map_err(error)?;
                }
                Cells::Numbers(v) => {
                    let values: Vec<f64> = v.iter().flatten().copied().collect();
                    let defined = levels(v.iter().map(Option::is_some).collect());
                    (column_writer.typed::<DoubleType>())
                        .write_batch(&values, Some(&defined), None)
                        .map_err(error)?;
                }
                Cells::Texts(v) => {
                    let values: Vec<ByteArray> = (v.iter().flatten())
                        .map(|s| ByteArray::from(s.as_str()))
                        .collect();
                    let defined = levels(v.iter().map(Option::is_some).collect());
                    (column_writer.typed::<ByteArrayType>())
                        .write_batch(&values, Some(&defined), None)
                        .map_err(error)?;
                }
            }
            column_writer.close().map_err(error)?;
        }
        group.close().map_err(error)?;
        writer.close().map_err(error)?;
        Ok(())
    }

    /// Reads a Parquet file this module wrote (or one of the same columns), each column's type
    /// given by its name.
    pub fn read_parquet(path: &Path, kind_of: fn(&str) -> Kind) -> Result<Table, String> {
        let error = |e: parquet::errors::ParquetError| e.to_string();
        let file = File::open(path).map_err(|e| e.to_string())?;
        let reader = SerializedFileReader::new(file).map_err(error)?;
        let schema = reader.metadata().file_metadata().schema_descr();
        let mut columns: Vec<Column> = (schema.columns().iter())
            .map(|c| {
                let name = c.name().to_string();
                Column {
                    kind: kind_of(&name),
                    cells: Cells::empty(kind_of(&name)),
                    name,
                }
            })
            .collect();
        for row in reader.get_row_iter(None).map_err(error)? {
            let row = row.map_err(error)?;
            for (column, (_, field)) in columns.iter_mut().zip(row.get_column_iter()) {
                let wrong = || format!("the column `{}` holds {field:?}", column.name);
                match (&mut column.cells, field) {
                    (Cells::Integers(v), Field::Null) => v.push(None),
                    (Cells::Integers(v), Field::Long(x)) => v.push(Some(*x)),
                    (Cells::Numbers(v), Field::Null) => v.push(None),
                    (Cells::Numbers(v), Field::Double(x)) => v.push(Some(*x)),
                    (Cells::Texts(v), Field::Null) => v.push(None),
                    (Cells::Texts(v), Field::Str(s)) => v.push(Some(s.clone())),
                    _ => return Err(wrong()),
                }
            }
        }
        Ok(Table { columns })
    }

    /// Writes the table to `path` in `format` (`TableFormat::of` a path: the format its
    /// extension names).
    pub fn write(&self, path: &Path, format: TableFormat) -> Result<(), String> {
        match format {
            TableFormat::Parquet => self.write_parquet(path),
            TableFormat::Csv => std::fs::write(path, self.to_csv()).map_err(|e| e.to_string()),
        }
    }

    /// Reads the table at `path` in the format its extension names.
    pub fn read(path: &Path, kind_of: fn(&str) -> Kind) -> Result<Table, String> {
        match TableFormat::of(path) {
            TableFormat::Parquet => Table::read_parquet(path, kind_of),
            TableFormat::Csv => {
                let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
                Table::from_csv(&text, kind_of)
            }
        }
    }
}

/// A field as CSV writes it: quoted when it holds a comma, a quote or a line break (its
/// quotes doubled).
fn quoted(text: &str) -> String {
    match text.contains([',', '"', '\n', '\r']) {
        true => format!("\"{}\"", text.replace('"', "\"\"")),
        false => text.to_string(),
    }
}

/// The records of a CSV text, quoted fields unquoted (RFC 4180).
fn csv_records(text: &str) -> Result<Vec<Vec<String>>, String> {
    let mut records = Vec::new();
    let (mut record, mut field) = (Vec::new(), String::new());
    let mut chars = text.chars().peekable();
    let mut in_quotes = false;
    let mut line = 1;
    while let Some(c) = chars.next() {
        match (in_quotes, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                field.push('"');
            }
            (true, '"') => in_quotes = false,
            (true, c) => {
                line += usize::from(c == '\n');
                field.push(c);
            }
            (false, '"') if field.is_empty() => in_quotes = true,
            (false, ',') => record.push(std::mem::take(&mut field)),
            (false, '\r') => {}
            (false, '\n') => {
                line += 1;
                record.push(std::mem::take(&mut field));
                records.push(std::mem::take(&mut record));
            }
            (false, c) => field.push(c),
        }
    }
    if in_quotes {
        return Err(format!("line {line}: a quoted field is not closed"));
    }
    if !field.is_empty() || !record.is_empty() {
        record.push(field);
        records.push(record);
    }
    Ok(records)
}
