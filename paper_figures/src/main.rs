//! Regenerates the thesis figures (placeholder until the figures issue lands).
fn main() {
    println!("paper_figures: figure regeneration is not implemented yet (see issue 5)");
}
