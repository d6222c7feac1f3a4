//! Tables for a paper: booktabs `tabular`s (`\toprule`, `\midrule`,
//! `\bottomrule`, Fear & Els, the booktabs manual) in plain ASCII, so that
//! pdfLaTeX, XeLaTeX and LuaLaTeX all compile them with `booktabs` alone.
//!
//! - Symbols are in math mode: Δ is `$\Delta$`, 𝓕 is `$\mathcal{F}$`, ≤ is
//!   `$\le$`, ...; a character with no LaTeX form here is an error in a
//!   test (`tests/latex.rs` compiles every table a run writes).
//! - Numbers in scientific notation are set as `$3.3\times10^{-9}$`.
//! - A table has at most [`MAX_COLUMNS`] columns (a page's width); what
//!   varies down a table goes into group rows ([`Tabular::group`]).
//! - Markdown emphasis and code marks are dropped.

/// The widest table a page holds in a journal's text width.
pub const MAX_COLUMNS: usize = 8;

/// A booktabs table: a header, then rows, optionally in titled groups.
#[derive(Clone, Debug)]
pub struct Tabular {
    comment: String,
    header: Vec<String>,
    lines: Vec<Line>,
}

#[derive(Clone, Debug)]
enum Line {
    Group(String),
    Row(Vec<String>),
}

impl Tabular {
    /// A table with `header` (LaTeX: see [`math`] and [`text`]) and a `%`
    /// comment line above it saying what it is.
    pub fn new(comment: &str, header: Vec<String>) -> Self {
        Self {
            comment: comment.replace('\n', " "),
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

    /// The `tabular`: columns whose cells are all numbers right-aligned.
    pub fn render(&self) -> String {
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
            "% {}\n\\begin{{tabular}}{{{spec}}}\n\\toprule\n{} \\\\\n",
            text(&self.comment),
            self.header.join(" & ")
        );
        out += "\\midrule\n";
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

/// A cell that reads as a number: `$...$` math of a number, or digits.
fn is_number_cell(cell: &str) -> bool {
    let c = cell.trim();
    let bare = c.trim_matches('$');
    bare.split_whitespace().next().is_some_and(|w| {
        let mantissa = w.split("\\times10^").next().unwrap_or(w);
        mantissa.trim_end_matches("\\%").parse::<f64>().is_ok()
    })
}

/// `x` as LaTeX math: `$3.3\times10^{-9}$` (two significant digits), `$0$`,
/// or plain digits for numbers between 0.01 and 10⁴.
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
        Ok(e) => format!("${mantissa}\\times10^{{{e}}}$"),
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

/// The first Markdown table in `markdown` as a booktabs `tabular`, with
/// `comment` on a `%` line above it.
pub fn booktabs(markdown: &str, comment: &str) -> String {
    let lines: Vec<&str> = markdown
        .lines()
        .skip_while(|l| !l.trim_start().starts_with('|'))
        .take_while(|l| l.trim_start().starts_with('|'))
        .collect();
    let Some((head, rest)) = lines.split_first() else {
        return format!("% {}: no table\n", text(comment));
    };
    let mut table = Tabular::new(comment, cells(head));
    for l in rest {
        if !l.replace(['|', '-', ':', ' '], "").is_empty() {
            table.row(cells(l));
        }
    }
    table.render()
}

/// A whole LaTeX document of `tables` (file names, `\input` from the same
/// folder): what a test compiles, and a template for a paper's preamble.
pub fn document(tables: &[&str]) -> String {
    let mut out = String::from(
        "\\documentclass{article}\n\\usepackage{booktabs}\n\\usepackage[margin=2cm]{geometry}\n\\begin{document}\n",
    );
    for t in tables {
        out += &format!("\\begin{{table}}[h]\\centering\\small\n\\input{{{t}}}\n\\end{{table}}\n");
    }
    out + "\\end{document}\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_markdown_table_becomes_booktabs() {
        let md = "Some text\n\n| solver | Δp | note |\n|---|---|---|\n| `newton_x` | 1.5e-8 | **wrong** & 50% |\n| b | 2 | c |\n\nafter";
        let tex = booktabs(md, "a test");
        assert!(
            tex.starts_with(
                "% a test\n\\begin{tabular}{lrl}\n\\toprule\nsolver & $\\Delta$p & note \\\\\n\\midrule\n"
            ),
            "{tex}"
        );
        assert!(
            tex.contains("newton\\_x & $1.5\\times10^{-8}$ & wrong \\& 50\\% \\\\"),
            "{tex}"
        );
        assert!(tex.ends_with("\\bottomrule\n\\end{tabular}\n"));
        assert!(tex.is_ascii());
    }

    #[test]
    fn numbers_are_set_in_math_and_words_are_left_alone() {
        assert_eq!(number(3.3e-9), "$3.3\\times10^{-9}$");
        assert_eq!(number(0.0), "$0$");
        assert_eq!(number(2.5), "$2.5$");
        assert_eq!(number(f64::NAN), "--");
        assert_eq!(text("0.0e0"), "$0.0$");
        assert_eq!(text("-2.0e-3 (a1e5)"), "$-2.0\\times10^{-3}$ (a1e5)");
        assert_eq!(
            text("r = 1e12, ε ≤ 1e-4"),
            "r = $1\\times10^{12}$, $\\varepsilon$ $\\le$ $1\\times10^{-4}$"
        );
        assert_eq!(text("1/64"), "1/64");
        assert_eq!(
            text("[0.8283, 1.0000] (17.2%)"),
            "[0.8283, 1.0000] (17.2\\%)"
        );
    }

    #[test]
    fn groups_span_the_table_between_rules() {
        let mut t = Tabular::new("t", vec!["a".into(), "b".into()]);
        t.group("Problem 1".into());
        t.row(vec!["x".into(), number(1e-3)]);
        t.group("Problem 2".into());
        t.row(vec!["y".into(), number(2e-3)]);
        let tex = t.render();
        assert!(tex.contains("{lr}"), "{tex}");
        assert!(
            tex.contains("\\midrule\n\\multicolumn{2}{l}{Problem 1} \\\\\nx & $1.0\\times10^{-3}$ \\\\\n\\midrule\n\\multicolumn{2}{l}{Problem 2}"),
            "{tex}"
        );
    }
}
