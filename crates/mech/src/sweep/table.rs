//! The table of a sweep: its CSV header (columns and provenance), one row per
//! run, its whole text read and written, and the merge of the shards' tables.

use super::grid::{parse_axes, Axis, Shard};
use super::{SweepError, CSV_MAGIC};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// One row of a sweep's table.
#[derive(Debug, Clone, PartialEq)]
pub struct TableRow {
    /// The run index in the whole grid.
    pub run: usize,
    /// Every numeric column between `run` and `failure`.
    pub values: Vec<f64>,
    /// Why the run failed (empty when it did not).
    pub failure: String,
}

impl TableRow {
    /// Appends the row's CSV line, newline included, to `out`. Numbers print in
    /// the shortest form that reads back exactly (`1e-10`, `0.5`, `NaN`).
    pub fn write_csv(&self, out: &mut String) {
        let _ = write!(out, "{}", self.run);
        for v in &self.values {
            let _ = write!(out, ",{v:?}");
        }
        out.push(',');
        out.push_str(&csv_field(&self.failure));
        out.push('\n');
    }

    /// Reads one line that [`TableRow::write_csv`] wrote (without its newline),
    /// under `header`; `file` and `line_no` name it in errors.
    pub fn parse(line: &str, header: &SweepHeader, file: &str, line_no: usize) -> Result<TableRow, SweepError> {
        let err = |reason: String| SweepError::Table { file: file.to_string(), line: line_no, reason };
        let columns = &header.columns;
        let n_values = columns.len() - 2;
        let mut fields = line.splitn(n_values + 2, ',');
        let run = fields
            .next()
            .and_then(|f| f.parse::<usize>().ok())
            .ok_or_else(|| err("the run index is not a whole number".into()))?;
        let mut values = Vec::with_capacity(n_values);
        for c in 0..n_values {
            let field = fields.next().ok_or_else(|| err(format!("{} columns expected", columns.len())))?;
            let v = field
                .parse::<f64>()
                .map_err(|_| err(format!("'{field}' in column '{}' is not a number", columns[c + 1])))?;
            values.push(v);
        }
        let last = fields.next().ok_or_else(|| err(format!("{} columns expected", columns.len())))?;
        let failure = failure_field(last).ok_or_else(|| {
            err(format!(
                "{} columns expected: the last, 'failure', is empty, text without commas or quotes, or quoted; found '{last}'",
                columns.len()
            ))
        })?;
        Ok(TableRow { run, values, failure })
    }
}

/// The first two lines of a sweep's CSV: the provenance comment and the
/// column names. Two sweeps with equal headers compute equal rows.
///
/// Columns: `run`, the grid's names (inputs), `t_final`, `final_<q>` per
/// coordinate, `final_<q>'` per velocity, `energy_drift`, `lyapunov`, `failure`.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepHeader {
    /// Provenance as `key=value` pairs (`model`, `grid`, `runs`, `until`, `method`,
    /// `rtol`, `atol`, `parameters`, `lyapunov`, and `shard` for a part).
    pub meta: Vec<(String, String)>,
    /// Column names, `run` first and `failure` last.
    pub columns: Vec<String>,
}

impl SweepHeader {
    /// A provenance value.
    pub fn meta(&self, key: &str) -> Option<&str> {
        self.meta.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    /// The number of runs of the whole sweep (from the provenance).
    pub fn total_runs(&self) -> Option<usize> {
        self.meta("runs")?.parse().ok()
    }

    /// The grid's axes (from the provenance).
    pub fn axes(&self) -> Option<Vec<Axis>> {
        parse_axes(self.meta("grid")?).ok()
    }

    /// The index into [`TableRow::values`] of a column (`None` for `run`, `failure` or an unknown name).
    pub fn value_index(&self, column: &str) -> Option<usize> {
        let k = self.columns.iter().position(|c| c == column)?;
        (k >= 1 && k + 1 < self.columns.len()).then(|| k - 1)
    }

    /// The two header lines, each ending in a newline.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(CSV_MAGIC);
        for (k, v) in &self.meta {
            let _ = write!(s, "; {k}={v}");
        }
        s.push('\n');
        s.push_str(&self.columns.join(","));
        s.push('\n');
        s
    }

    /// Reads the two lines [`SweepHeader::to_csv`] writes (without their
    /// newlines); `file` names them in errors.
    pub fn parse(first: &str, second: &str, file: &str) -> Result<SweepHeader, SweepError> {
        let err = |line: usize, reason: String| SweepError::Table { file: file.to_string(), line, reason };
        let Some(rest) = first.strip_prefix(CSV_MAGIC) else {
            return Err(err(1, format!("not a sweep's table (the first line should start with '{CSV_MAGIC}')")));
        };
        let mut meta = Vec::new();
        for pair in rest.split("; ").map(str::trim).filter(|p| !p.is_empty()) {
            let (k, v) = pair.split_once('=').ok_or_else(|| err(1, format!("provenance '{pair}' is not KEY=VALUE")))?;
            meta.push((k.to_string(), v.to_string()));
        }
        let columns: Vec<String> = second.split(',').map(str::to_string).collect();
        if columns.len() < 2 || columns[0] != "run" || columns.last().map(String::as_str) != Some("failure") {
            return Err(err(2, "the header should start with 'run' and end with 'failure'".into()));
        }
        Ok(SweepHeader { meta, columns })
    }
}

/// A sweep's result held whole: its header and rows, in run order. Its file
/// form is CSV with one comment line of provenance first ([`SweepTable::to_csv`]).
/// A sweep streams its rows ([`Sweep::run`]); a table is for what needs them
/// all at once ([`merge`], tests).
#[derive(Debug, Clone, PartialEq)]
pub struct SweepTable {
    /// Provenance and columns.
    pub header: SweepHeader,
    /// The rows, ascending by run.
    pub rows: Vec<TableRow>,
}

impl SweepTable {
    /// The CSV text: the provenance comment, the header and one line per row.
    pub fn to_csv(&self) -> String {
        let mut s = self.header.to_csv();
        s.reserve(64 * self.rows.len());
        for row in &self.rows {
            row.write_csv(&mut s);
        }
        s
    }

    /// Reads the text [`SweepTable::to_csv`] writes; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<SweepTable, SweepError> {
        let mut lines = text.lines();
        let first = lines.next().unwrap_or_default();
        let header = SweepHeader::parse(first, lines.next().unwrap_or_default(), file)?;
        let mut rows = Vec::new();
        for (k, line) in lines.enumerate() {
            if !line.is_empty() {
                rows.push(TableRow::parse(line, &header, file, k + 3)?);
            }
        }
        Ok(SweepTable { header, rows })
    }
}

/// A CSV field: quoted when it holds a comma, a quote or a line break (which
/// becomes a space: one row per line).
pub(super) fn csv_field(text: &str) -> String {
    let text = text.replace(['\n', '\r'], " ");
    if text.contains([',', '"']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text
    }
}

/// The text of the last field of a row as [`csv_field`] writes it: plain text
/// without commas or quotes, or one quoted field whose quotes inside are doubled.
/// None for anything else (extra columns, a stray quote).
pub(super) fn failure_field(field: &str) -> Option<String> {
    match field.strip_prefix('"') {
        None => (!field.contains([',', '"'])).then(|| field.to_string()),
        Some(rest) => {
            let inner = rest.strip_suffix('"')?;
            (!inner.replace("\"\"", "").contains('"')).then(|| inner.replace("\"\"", "\""))
        }
    }
}

/// Joins the tables of a sweep's shards (`name`, table) into the table of the
/// whole sweep, rows sorted by run. Fails when the shards come from different
/// sweeps (columns or provenance differ), when a shard or a run appears twice,
/// or when runs are missing.
pub fn merge(shards: &[(String, SweepTable)]) -> Result<SweepTable, SweepError> {
    let Some((first_name, first)) = shards.first() else {
        return Err(SweepError::NothingToMerge);
    };
    let whole = |t: &SweepTable| -> Vec<(String, String)> {
        t.header.meta.iter().filter(|(k, _)| k != "shard").cloned().collect()
    };
    let meta = whole(first);
    let total = first.header.total_runs().ok_or_else(|| SweepError::Table {
        file: first_name.clone(),
        line: 1,
        reason: "the provenance line has no 'runs='".into(),
    })?;
    let shard_of = |name: &str, t: &SweepTable| -> Result<Shard, SweepError> {
        match t.header.meta("shard") {
            None => Ok(Shard::default()),
            Some(text) => Shard::parse(text).map_err(|_| SweepError::Table {
                file: name.to_string(),
                line: 1,
                reason: format!("'shard={text}' is not I/N"),
            }),
        }
    };
    let count = shard_of(first_name, first)?.count;
    let mut seen: BTreeMap<usize, &str> = BTreeMap::new();
    let mut rows: Vec<(usize, &str, &TableRow)> = Vec::new();
    for (name, table) in shards {
        let mismatch = |reason: String| SweepError::Mismatch { first: first_name.clone(), file: name.clone(), reason };
        if table.header.columns != first.header.columns {
            return Err(mismatch(format!(
                "its columns are {} instead of {}",
                table.header.columns.join(","),
                first.header.columns.join(",")
            )));
        }
        let other = whole(table);
        if other != meta {
            let keys: Vec<&String> = meta.iter().chain(&other).map(|(k, _)| k).collect();
            let value = |m: &[(String, String)], k: &str| m.iter().find(|(kk, _)| kk == k).map(|(_, v)| v.clone());
            let key = keys.into_iter().find(|k| value(&meta, k) != value(&other, k)).cloned().unwrap_or_default();
            return Err(mismatch(format!(
                "{key} is '{}' there and '{}' here",
                value(&meta, &key).unwrap_or_default(),
                value(&other, &key).unwrap_or_default()
            )));
        }
        let shard = shard_of(name, table)?;
        if shard.count != count {
            return Err(mismatch(format!("it is one of {} shards, not of {count}", shard.count)));
        }
        if let Some(previous) = seen.insert(shard.index, name) {
            return Err(SweepError::Mismatch {
                first: previous.to_string(),
                file: name.clone(),
                reason: format!("both are shard {shard}"),
            });
        }
        for (k, row) in table.rows.iter().enumerate() {
            if row.run >= total || row.run % shard.count != shard.index {
                return Err(SweepError::Table {
                    file: name.clone(),
                    line: k + 3,
                    reason: format!("run {} does not belong to shard {shard} of {total} runs", row.run),
                });
            }
            rows.push((row.run, name, row));
        }
    }
    rows.sort_by_key(|r| r.0);
    for pair in rows.windows(2) {
        if pair[0].0 == pair[1].0 {
            return Err(SweepError::DuplicateRun {
                run: pair[0].0,
                first: pair[0].1.to_string(),
                second: pair[1].1.to_string(),
            });
        }
    }
    if rows.len() != total {
        let present: Vec<usize> = rows.iter().map(|r| r.0).collect();
        let missing: Vec<usize> = (0..total).filter(|r| present.binary_search(r).is_err()).collect();
        let mut absent: Vec<String> =
            (0..count).filter(|i| !seen.contains_key(i)).map(|i| Shard { index: i, count }.to_string()).collect();
        if absent.is_empty() {
            absent.push("none (rows are missing from the shard files)".into());
        }
        return Err(SweepError::MissingRuns {
            count: missing.len(),
            total,
            first: missing.iter().take(5).copied().collect(),
            shards: absent.join(", "),
        });
    }
    let header = SweepHeader { meta, columns: first.header.columns.clone() };
    Ok(SweepTable { header, rows: rows.into_iter().map(|r| r.2.clone()).collect() })
}
