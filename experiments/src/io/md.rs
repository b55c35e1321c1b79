//! Markdown tables for the book's generated snippets. The header and every row are arrays of
//! the same length `N`, so a table cannot fall out of step with its header.

/// A Markdown table with `N` columns.
#[derive(Debug, Clone)]
pub struct Table<const N: usize> {
    header: [String; N],
    rows: Vec<[String; N]>,
}

impl<const N: usize> Table<N> {
    /// A table with this header.
    pub fn new(header: [&str; N]) -> Self {
        Self {
            header: header.map(str::to_string),
            rows: Vec::new(),
        }
    }

    /// Appends a row.
    pub fn row(&mut self, cells: [String; N]) -> &mut Self {
        self.rows.push(cells);
        self
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True without rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The table as Markdown (a `|` inside a cell is escaped, and `<` and `>` are written
    /// as [`plain`] writes them).
    pub fn render(&self) -> String {
        let line = |cells: &[String; N]| {
            let esc: Vec<String> = cells.iter().map(|c| plain(c).replace('|', "\\|")).collect();
            format!("| {} |\n", esc.join(" | "))
        };
        let mut s = line(&self.header);
        s.push_str(&format!("|{}\n", "---|".repeat(N)));
        for r in &self.rows {
            s.push_str(&line(r));
        }
        s
    }
}

/// Text for Markdown prose or a table cell with `<` and `>` as character references, so that
/// a quantity such as `m<a v>` (a mean of a product) reads as written rather than as an HTML
/// tag that swallows the text after it.
pub fn plain(text: &str) -> String {
    text.replace('<', "&lt;").replace('>', "&gt;")
}

/// The cells `lead` followed by the cells `rest`, as one header or row of `N = A + B` cells
/// (for a table whose leading columns differ between figures); a wrong `N` does not compile.
pub fn join<T, const A: usize, const B: usize, const N: usize>(
    lead: [T; A],
    rest: [T; B],
) -> [T; N] {
    const {
        assert!(
            A + B == N,
            "a joined row has as many cells as its two parts"
        )
    };
    let mut cells = lead.into_iter().chain(rest);
    std::array::from_fn(|_| cells.next().expect("A + B == N cells"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_header_rule_and_rows() {
        let mut t = Table::new(["claim", "ours"]);
        t.row(["F8-c".into(), "1 | 2".into()]);
        assert_eq!(
            t.render(),
            "| claim | ours |\n|---|---|\n| F8-c | 1 \\| 2 |\n"
        );
    }

    #[test]
    fn angle_brackets_in_a_cell_are_not_a_tag() {
        let mut t = Table::new(["quantity"]);
        t.row(["mean drive power m<a v> (W)".into()]);
        assert!(t.render().contains("m&lt;a v&gt; (W)"), "{}", t.render());
    }

    #[test]
    fn join_keeps_the_order_of_both_parts() {
        let joined: [&str; 5] = join(["set", "curve"], ["a", "b", "c"]);
        assert_eq!(joined, ["set", "curve", "a", "b", "c"]);
    }
}
