//! One generic writer from rows to a data frame: every table of the experiments is a list of
//! rows, each a list of `(column name, cell)` pairs built with [`row!`](crate::row), and
//! [`frame`] turns them into a polars `DataFrame` with one typed column per name. Column names
//! carry their units (`freq_hz`, `v1_rms_v`); a missing value is an explicit `None` (null), a
//! NaN stays a NaN.

use anyhow::{bail, Result};
use polars::prelude::*;

/// One cell of a row.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// A float; `None` is written as null.
    F64(Option<f64>),
    /// An unsigned count.
    U32(u32),
    /// An unsigned 64-bit integer (seeds, streams, step counts).
    U64(u64),
    /// A signed integer.
    I64(i64),
    /// A flag.
    Bool(bool),
    /// A label.
    Str(String),
}

impl From<f64> for Cell {
    fn from(v: f64) -> Self {
        Cell::F64(Some(v))
    }
}
impl From<Option<f64>> for Cell {
    fn from(v: Option<f64>) -> Self {
        Cell::F64(v)
    }
}
impl From<u32> for Cell {
    fn from(v: u32) -> Self {
        Cell::U32(v)
    }
}
impl From<u64> for Cell {
    fn from(v: u64) -> Self {
        Cell::U64(v)
    }
}
impl From<usize> for Cell {
    fn from(v: usize) -> Self {
        Cell::U64(v as u64)
    }
}
impl From<i64> for Cell {
    fn from(v: i64) -> Self {
        Cell::I64(v)
    }
}
impl From<bool> for Cell {
    fn from(v: bool) -> Self {
        Cell::Bool(v)
    }
}
impl From<String> for Cell {
    fn from(v: String) -> Self {
        Cell::Str(v)
    }
}
impl From<&str> for Cell {
    fn from(v: &str) -> Self {
        Cell::Str(v.to_string())
    }
}

/// A row: `(column name, cell)` pairs, in column order.
pub type Row = Vec<(&'static str, Cell)>;

/// A column name made at run time (a device file's mass names) as a [`Row`]'s `&'static str`:
/// each distinct name is leaked once and shared after, so a run leaks a handful of short
/// strings however many rows it writes.
pub fn column_name(name: &str) -> &'static str {
    use std::collections::BTreeSet;
    use std::sync::Mutex;
    static NAMES: Mutex<BTreeSet<&'static str>> = Mutex::new(BTreeSet::new());
    let mut names = NAMES
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    match names.get(name) {
        Some(n) => n,
        None => {
            let n: &'static str = Box::leak(name.to_string().into_boxed_str());
            names.insert(n);
            n
        }
    }
}

/// Builds a [`Row`]: `row!["freq_hz" => f, "series" => label]`.
#[macro_export]
macro_rules! row {
    ($($name:expr => $value:expr),* $(,)?) => {
        vec![$(($name, $crate::io::frame::Cell::from($value))),*]
    };
}

enum Buf {
    F64(Vec<Option<f64>>),
    U32(Vec<u32>),
    U64(Vec<u64>),
    I64(Vec<i64>),
    Bool(Vec<bool>),
    Str(Vec<String>),
}

impl Buf {
    fn of(cell: &Cell) -> Self {
        match cell {
            Cell::F64(_) => Buf::F64(Vec::new()),
            Cell::U32(_) => Buf::U32(Vec::new()),
            Cell::U64(_) => Buf::U64(Vec::new()),
            Cell::I64(_) => Buf::I64(Vec::new()),
            Cell::Bool(_) => Buf::Bool(Vec::new()),
            Cell::Str(_) => Buf::Str(Vec::new()),
        }
    }

    fn push(&mut self, cell: Cell) -> bool {
        match (self, cell) {
            (Buf::F64(v), Cell::F64(x)) => v.push(x),
            (Buf::U32(v), Cell::U32(x)) => v.push(x),
            (Buf::U64(v), Cell::U64(x)) => v.push(x),
            (Buf::I64(v), Cell::I64(x)) => v.push(x),
            (Buf::Bool(v), Cell::Bool(x)) => v.push(x),
            (Buf::Str(v), Cell::Str(x)) => v.push(x),
            _ => return false,
        }
        true
    }

    fn column(self, name: &str) -> Column {
        let name: PlSmallStr = name.into();
        match self {
            Buf::F64(v) => Series::new(name, v),
            Buf::U32(v) => Series::new(name, v),
            Buf::U64(v) => Series::new(name, v),
            Buf::I64(v) => Series::new(name, v),
            Buf::Bool(v) => Series::new(name, v),
            Buf::Str(v) => Series::new(name, v),
        }
        .into()
    }
}

/// The data frame of `rows`. Every row must have the columns of the first, in the same order
/// and with the same cell types; the error names the row and the column otherwise. A table
/// without rows is an error too (it would have no columns).
pub fn frame(rows: impl IntoIterator<Item = Row>) -> Result<DataFrame> {
    let mut names: Vec<&'static str> = Vec::new();
    let mut cols: Vec<Buf> = Vec::new();
    for (i, row) in rows.into_iter().enumerate() {
        if i == 0 {
            names = row.iter().map(|(n, _)| *n).collect();
            cols = row.iter().map(|(_, c)| Buf::of(c)).collect();
        }
        if row.len() != names.len() || row.iter().zip(&names).any(|((a, _), b)| a != b) {
            let got: Vec<&str> = row.iter().map(|(n, _)| *n).collect();
            bail!("row {i} has columns {got:?}, expected {names:?}");
        }
        for ((name, cell), col) in row.into_iter().zip(cols.iter_mut()) {
            let shown = format!("{cell:?}");
            if !col.push(cell) {
                bail!("row {i}, column `{name}`: cell {shown} has another type than row 0's");
            }
        }
    }
    if names.is_empty() {
        bail!("a table without rows has no columns");
    }
    let columns: Vec<Column> = cols
        .into_iter()
        .zip(&names)
        .map(|(c, n)| c.column(n))
        .collect();
    Ok(DataFrame::new(columns)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_become_typed_columns() {
        let rows = (0..3).map(|i| {
            crate::row![
                "freq_hz" => 100.0 * i as f64,
                "end_hz" => (i > 0).then_some(1.5),
                "series" => format!("s{i}"),
                "converged" => i != 1,
                "blocks" => i as u32,
            ]
        });
        let df = frame(rows).unwrap();
        assert_eq!(df.shape(), (3, 5));
        assert_eq!(df.column("end_hz").unwrap().null_count(), 1);
        assert_eq!(df.column("blocks").unwrap().dtype(), &DataType::UInt32);
        assert_eq!(df.column("series").unwrap().dtype(), &DataType::String);
    }

    #[test]
    fn mismatched_rows_are_errors_naming_the_row() {
        let rows = vec![crate::row!["a" => 1.0], crate::row!["b" => 1.0]];
        let e = frame(rows).unwrap_err().to_string();
        assert!(e.contains("row 1") && e.contains("\"b\""), "{e}");
        let rows = vec![crate::row!["a" => 1.0], crate::row!["a" => "x"]];
        let e = frame(rows).unwrap_err().to_string();
        assert!(e.contains("column `a`"), "{e}");
        assert!(frame(Vec::<Row>::new()).is_err());
    }
}
