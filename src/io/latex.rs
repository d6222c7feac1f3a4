//! LaTeX versions of the Markdown tables: a `tabular` with booktabs rules
//! (`\toprule`, `\midrule`, `\bottomrule`), text escaped for LaTeX and kept
//! in UTF-8 (compile with XeLaTeX or LuaLaTeX, or pdfLaTeX with inputenc),
//! Markdown emphasis and code marks removed.

/// Escapes LaTeX's special characters and drops Markdown marks.
fn escape(cell: &str) -> String {
    let plain = cell.trim().replace("**", "").replace('`', "");
    let mut out = String::with_capacity(plain.len());
    for c in plain.chars() {
        match c {
            '\\' => out.push_str("\\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            '~' => out.push_str("\\textasciitilde{}"),
            '^' => out.push_str("\\textasciicircum{}"),
            _ => out.push(c),
        }
    }
    out
}

fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
    inner.split('|').map(escape).collect()
}

/// The first Markdown table in `markdown` as a booktabs `tabular`, with
/// `comment` on a `%` line above it. Columns whose cells all read as
/// numbers are right-aligned.
pub fn booktabs(markdown: &str, comment: &str) -> String {
    let lines: Vec<&str> = markdown
        .lines()
        .skip_while(|l| !l.trim_start().starts_with('|'))
        .take_while(|l| l.trim_start().starts_with('|'))
        .collect();
    let Some((head, rest)) = lines.split_first() else {
        return format!("% {comment}: no table\n");
    };
    let header = cells(head);
    let rows: Vec<Vec<String>> = rest
        .iter()
        .filter(|l| !l.replace(['|', '-', ':', ' '], "").is_empty())
        .map(|l| cells(l))
        .collect();
    let numeric = |j: usize| {
        rows.iter().all(|r| {
            r.get(j).is_some_and(|c| {
                c.split_whitespace()
                    .next()
                    .is_some_and(|w| w.trim_end_matches('%').parse::<f64>().is_ok())
            })
        })
    };
    let spec: String = (0..header.len())
        .map(|j| if numeric(j) { 'r' } else { 'l' })
        .collect();
    let mut out = format!(
        "% {comment}\n\\begin{{tabular}}{{{spec}}}\n\\toprule\n{} \\\\\n\\midrule\n",
        header.join(" & ")
    );
    for r in rows {
        out += &format!("{} \\\\\n", r.join(" & "));
    }
    out + "\\bottomrule\n\\end{tabular}\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_markdown_table_becomes_booktabs() {
        let md = "Some text\n\n| solver | Δp | note |\n|---|---|---|\n| `newton_x` | 1.5e-8 | **wrong** & 50% |\n| b | 2 | c |\n\nafter";
        let tex = booktabs(md, "a test");
        assert!(tex.starts_with(
            "% a test\n\\begin{tabular}{lrl}\n\\toprule\nsolver & Δp & note \\\\\n\\midrule\n"
        ));
        assert!(tex.contains("newton\\_x & 1.5e-8 & wrong \\& 50\\% \\\\"));
        assert!(tex.ends_with("\\bottomrule\n\\end{tabular}\n"));
    }
}
