//! The live UI of the plug-in binary end to end: the hand works with its solver as with the
//! built-in ones, without the solver knowing of it.

#[path = "../../../crates/clothsim/tests/support/mod.rs"]
mod support;

#[test]
fn the_mouse_grabs_drags_and_lets_go_a_point_under_xpbd() {
    let bin = env!("CARGO_BIN_EXE_clothsim-xpbd");
    let Some(t) = support::Tmux::open(bin, "hand-xpbd", 100, 30) else {
        return;
    };
    support::hands::a_point_is_grabbed_dragged_and_let_go(&t, "tui pinned4 --paused --solver xpbd");
}
