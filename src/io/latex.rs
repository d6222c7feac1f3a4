//! Tables for a paper: booktabs tables (`\toprule`, `\midrule`,
//! `\bottomrule`, Fear & Els, the booktabs manual) in plain ASCII, so that
//! pdfLaTeX, XeLaTeX and LuaLaTeX all compile them with `booktabs` alone.
//!
//! - Each is a `table` float with its `\caption` (above, as tables have
//!   it) and a `\label` (`tab:` and the file's name), set `\footnotesize`
//!   with 4 pt between columns so that it fits `\linewidth` of a default
//!   one-column `article` (345 pt); `tests/reproduce.rs` compiles every
//!   table a run writes into one and fails on any overfull box.
//! - Symbols are in math mode: Δ is `$\Delta$`, 𝓕 is `$\mathcal{F}$`, ≤ is
//!   `$\le$`, ...; a character with no LaTeX form here is an error in a
//!   test (`tests/latex.rs` compiles every table a run writes).
//! - Numbers in scientific notation are set compactly as `$3.3\mathrm{e}{-9}$`
//!   (3.3e−9), the width of a page being the tables' scarce resource.
//! - What varies down a table goes into group rows ([`Tabular::group`]).
//! - Markdown emphasis and code marks are dropped.

/// The most columns a table may have; whether it fits the page is the
/// compile test's to say (an overfull box fails it).
pub const MAX_COLUMNS: usize = 11;

/// A booktabs table: a caption, a header, then rows, optionally in titled
/// groups.
#[derive(Clone, Debug)]
pub struct Tabular {
    caption: String,
    label: String,
    header: Vec<String>,
    lines: Vec<Line>,
}

#[derive(Clone, Debug)]
enum Line {
    Group(String),
    Row(Vec<String>),
}

impl Tabular {
    /// A table with `header` (LaTeX: see [`math`] and [`text`]), its
    /// `caption` (plain text, set by [`text`]) and `label` (`tab:label`;
    /// letters, digits and `-` only, as the file's name without `.tex`).
    pub fn new(caption: &str, label: &str, header: Vec<String>) -> Self {
        Self {
            caption: caption.replace('\n', " "),
            label: label_of(label),
            header,
            lines: Vec::new(),
        }
    }

    /// The columns.
    pub fn columns(&self) -> usize {
        self.header.len()
    }

    /// A group row spanning the table (e.g. `Problem 1, $h = 1/64$`),
    /// above the rows that follow it.
    pub fn group(&mut self, title: String) {
        self.lines.push(Line::Group(title));
    }

    /// A row of LaTeX cells.
    pub fn row(&mut self, cells: Vec<String>) {
        self.lines.push(Line::Row(cells));
    }

    /// The `table` float around this table's `tabular`.
    pub fn render(&self) -> String {
        Self::stacked(std::slice::from_ref(self))
    }

    /// One `table` float holding `panels`' tabulars one above the other,
    /// with the first one's caption and label: a table with more columns
    /// than a page's width holds, in parts that share their first column.
    pub fn stacked(panels: &[Tabular]) -> String {
        let Some(first) = panels.first() else {
            return String::new();
        };
        let body: Vec<String> = panels.iter().map(Tabular::tabular).collect();
        format!(
            "% contactlab: needs \\usepackage{{booktabs}}\n\\begin{{table}}[htbp]\n\\centering\n\\footnotesize\n\
             \\setlength{{\\tabcolsep}}{{4pt}}\n\\caption{{{}}}\n\\label{{tab:{}}}\n{}\\end{{table}}\n",
            text(&first.caption),
            first.label,
            body.join("\\par\\medskip\n")
        )
    }

    /// The `tabular`: columns whose cells are all numbers right-aligned.
    fn tabular(&self) -> String {
        let rows = || {
            self.lines.iter().filter_map(|l| match l {
                Line::Row(r) => Some(r),
                Line::Group(_) => None,
            })
        };
        let spec: String = (0..self.columns())
            .map(|j| {
                let numeric = rows().all(|r| r.get(j).is_some_and(|c| is_number_cell(c)));
                if numeric && rows().next().is_some() {
                    'r'
                } else {
                    'l'
                }
            })
            .collect();
        let mut out = format!(
            "\\begin{{tabular}}{{{spec}}}\n\\toprule\n{} \\\\\n\\midrule\n",
            self.header.join(" & ")
        );
        for (k, line) in self.lines.iter().enumerate() {
            match line {
                Line::Group(title) => {
                    // A group below rows is set off by a rule of its own.
                    if k > 0 {
                        out += "\\midrule\n";
                    }
                    out += &format!("\\multicolumn{{{}}}{{l}}{{{title}}} \\\\\n", self.columns());
                }
                Line::Row(cells) => out += &format!("{} \\\\\n", cells.join(" & ")),
            }
        }
        out + "\\bottomrule\n\\end{tabular}\n"
    }
}

/// The solver's claims that differ from the certified status, each marked
/// on the status by a letter (a, b, …) and named once in the caption: a
/// claim column would not fit the page.
pub struct ClaimMarks<'a> {
    claims: Vec<&'a str>,
}

impl<'a> ClaimMarks<'a> {
    /// The marks of `(status, claim)` pairs, in the order first seen.
    pub fn of(pairs: impl IntoIterator<Item = (&'a str, &'a str)>) -> Self {
        let mut claims = Vec::new();
        for (status, claim) in pairs {
            if status != claim && !claims.contains(&claim) {
                claims.push(claim);
            }
        }
        Self { claims }
    }

    /// The status as a cell, with its claim's letter if they differ.
    pub fn status(&self, status: &str, claim: &str) -> String {
        match self.claims.iter().position(|c| *c == claim) {
            Some(k) if status != claim => format!("{}$^{}$", text(status), letter(k)),
            _ => text(status),
        }
    }

    /// For the caption: ` (a: the solver claimed converged; …)`, or
    /// nothing when every claim is its status.
    pub fn caption(&self) -> String {
        if self.claims.is_empty() {
            return String::new();
        }
        let named: Vec<String> = self
            .claims
            .iter()
            .enumerate()
            .map(|(k, c)| format!("{}: the solver claimed {c}", letter(k)))
            .collect();
        format!(" ({})", named.join("; "))
    }
}

/// The k-th mark: a, b, c, …
fn letter(k: usize) -> char {
    (b'a' + (k % 26) as u8) as char
}

/// A label's name: letters and digits kept, anything else `-`.
fn label_of(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect()
}

/// A cell that reads as a number: `$...$` math of a number, or digits.
fn is_number_cell(cell: &str) -> bool {
    let c = cell.trim();
    let bare = c.trim_matches('$');
    bare.split_whitespace().next().is_some_and(|w| {
        let mantissa = w.split("\\mathrm{e}").next().unwrap_or(w);
        mantissa.trim_end_matches("\\%").parse::<f64>().is_ok()
    })
}

/// `x` as LaTeX math: `$3.3\mathrm{e}{-9}$` (two significant digits),
/// `$0$`, or `$2.5$` without an exponent.
pub fn number(x: f64) -> String {
    if x == 0.0 {
        return "$0$".into();
    }
    if !x.is_finite() {
        return "--".into();
    }
    scientific(&format!("{x:.1e}"))
}

/// A scientific number as Rust writes it (`3.3e-9`, `1.0e0`) in LaTeX math.
fn scientific(s: &str) -> String {
    let (mantissa, exponent) = s.split_once('e').unwrap_or((s, "0"));
    match exponent.parse::<i32>() {
        Ok(0) => format!("${mantissa}$"),
        Ok(e) => format!("${mantissa}\\mathrm{{e}}{{{e}}}$"),
        Err(_) => text(s),
    }
}

/// A math formula as a cell: `math("\\Delta u/U")` is `$\Delta u/U$`.
pub fn math(formula: &str) -> String {
    format!("${formula}$")
}

/// The LaTeX form of a non-ASCII symbol used in contactlab's tables.
fn symbol(c: char) -> Option<&'static str> {
    Some(match c {
        'Δ' => "$\\Delta$",
        'ε' => "$\\varepsilon$",
        'λ' => "$\\lambda$",
        'μ' => "$\\mu$",
        'ν' => "$\\nu$",
        'ω' => "$\\omega$",
        'τ' => "$\\tau$",
        'Γ' => "$\\Gamma$",
        '𝓕' => "$\\mathcal{F}$",
        'ᵀ' => "$^{\\top}$",
        '≤' => "$\\le$",
        '≥' => "$\\ge$",
        '×' => "$\\times$",
        '·' => "$\\cdot$",
        '√' => "$\\surd$",
        '∞' => "$\\infty$",
        '→' => "$\\to$",
        '±' => "$\\pm$",
        '‖' => "$\\|$",
        '₂' => "$_2$",
        '–' => "--",
        '—' => "---",
        '…' => "\\dots{}",
        '’' => "'",
        '†' => "$^{\\dagger}$",
        _ => return None,
    })
}

/// Plain text as LaTeX: special characters escaped, symbols in math mode,
/// scientific numbers as [`number`] sets them, Markdown marks dropped.
/// A character with no LaTeX form here is kept (and fails the compile
/// test, which is where it should be found).
pub fn text(cell: &str) -> String {
    let plain = cell.trim().replace("**", "").replace('`', "");
    let mut out = String::with_capacity(plain.len() + 16);
    let chars: Vec<char> = plain.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        // A scientific number starts at a digit not inside a word.
        let starts_word = i == 0 || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '.');
        if starts_word && chars[i].is_ascii_digit() {
            let mut j = i;
            while j < chars.len() && (chars[j].is_ascii_digit() || chars[j] == '.') {
                j += 1;
            }
            if j < chars.len() && chars[j] == 'e' {
                let mut k = j + 1;
                if k < chars.len() && (chars[k] == '-' || chars[k] == '+') {
                    k += 1;
                }
                let digits = k;
                while k < chars.len() && chars[k].is_ascii_digit() {
                    k += 1;
                }
                let ends_word = k == chars.len() || !chars[k].is_alphanumeric();
                if k > digits && ends_word {
                    let s: String = chars[i..k].iter().collect();
                    let negative = i > 0 && chars[i - 1] == '-' && out.ends_with('-');
                    if negative {
                        out.pop();
                        out += &scientific(&format!("-{s}"));
                    } else {
                        out += &scientific(&s);
                    }
                    i = k;
                    continue;
                }
            }
            out.extend(&chars[i..j]);
            i = j;
            continue;
        }
        let c = chars[i];
        match c {
            '\\' => out.push_str("\\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            '~' => out.push_str("\\textasciitilde{}"),
            '^' => out.push_str("\\textasciicircum{}"),
            '<' => out.push_str("$<$"),
            '>' => out.push_str("$>$"),
            '|' => out.push_str("$|$"),
            c if c.is_ascii() => out.push(c),
            c => match symbol(c) {
                Some(s) => out.push_str(s),
                None => out.push(c),
            },
        }
        i += 1;
    }
    out
}

fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
    inner.split('|').map(text).collect()
}

/// The first Markdown table in `markdown` as a booktabs table with
/// `caption` and `label`.
pub fn booktabs(markdown: &str, caption: &str, label: &str) -> String {
    let lines: Vec<&str> = markdown
        .lines()
        .skip_while(|l| !l.trim_start().starts_with('|'))
        .take_while(|l| l.trim_start().starts_with('|'))
        .collect();
    let Some((head, rest)) = lines.split_first() else {
        return format!("% {}: no table\n", text(caption));
    };
    let mut table = Tabular::new(caption, label, cells(head));
    for l in rest {
        if !l.replace(['|', '-', ':', ' '], "").is_empty() {
            table.row(cells(l));
        }
    }
    table.render()
}

/// A whole LaTeX document of `tables` (file names, `\input` from the same
/// folder): a default one-column `article` with `booktabs`, what a test
/// compiles (an overfull box fails it), and a template for a paper's
/// preamble.
pub fn document(tables: &[&str]) -> String {
    let mut out =
        String::from("\\documentclass{article}\n\\usepackage{booktabs}\n\\begin{document}\n");
    for t in tables {
        out += &format!("\\input{{{t}}}\n");
    }
    out + "\\end{document}\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_markdown_table_becomes_booktabs() {
        let md = "Some text\n\n| solver | Δp | note |\n|---|---|---|\n| `newton_x` | 1.5e-8 | **wrong** & 50% |\n| b | 2 | c |\n\nafter";
        let tex = booktabs(md, "a test", "my_table");
        assert!(
            tex.contains(
                "\\caption{a test}\n\\label{tab:my-table}\n\\begin{tabular}{lrl}\n\\toprule\nsolver & $\\Delta$p & note \\\\\n\\midrule\n"
            ),
            "{tex}"
        );
        assert!(tex.contains("\\begin{table}"), "{tex}");
        assert!(
            tex.contains("newton\\_x & $1.5\\mathrm{e}{-8}$ & wrong \\& 50\\% \\\\"),
            "{tex}"
        );
        assert!(tex.ends_with("\\bottomrule\n\\end{tabular}\n\\end{table}\n"));
        assert!(tex.is_ascii());
    }

    #[test]
    fn numbers_are_set_in_math_and_words_are_left_alone() {
        assert_eq!(number(3.3e-9), "$3.3\\mathrm{e}{-9}$");
        assert_eq!(number(0.0), "$0$");
        assert_eq!(number(2.5), "$2.5$");
        assert_eq!(number(f64::NAN), "--");
        assert_eq!(text("0.0e0"), "$0.0$");
        assert_eq!(text("-2.0e-3 (a1e5)"), "$-2.0\\mathrm{e}{-3}$ (a1e5)");
        assert_eq!(
            text("r = 1e12, ε ≤ 1e-4"),
            "r = $1\\mathrm{e}{12}$, $\\varepsilon$ $\\le$ $1\\mathrm{e}{-4}$"
        );
        assert_eq!(text("1/64"), "1/64");
        assert_eq!(text("2.8e-3†"), "$2.8\\mathrm{e}{-3}$$^{\\dagger}$");
        assert_eq!(
            text("[0.8283, 1.0000] (17.2%)"),
            "[0.8283, 1.0000] (17.2\\%)"
        );
    }

    #[test]
    fn groups_span_the_table_between_rules() {
        let mut t = Tabular::new("t", "t", vec!["a".into(), "b".into()]);
        t.group("Problem 1".into());
        t.row(vec!["x".into(), number(1e-3)]);
        t.group("Problem 2".into());
        t.row(vec!["y".into(), number(2e-3)]);
        let tex = t.render();
        assert!(tex.contains("{lr}"), "{tex}");
        assert!(
            tex.contains("\\midrule\n\\multicolumn{2}{l}{Problem 1} \\\\\nx & $1.0\\mathrm{e}{-3}$ \\\\\n\\midrule\n\\multicolumn{2}{l}{Problem 2}"),
            "{tex}"
        );
    }
}
