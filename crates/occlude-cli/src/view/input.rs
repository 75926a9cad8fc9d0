//! The viewer's keys: held movement keys become a [`Movement`], pressed
//! command keys an [`Action`].

use super::camera_control::Movement;
use occlude_core::methods::METHOD_NAMES;
use std::collections::HashSet;
use winit::keyboard::KeyCode;

/// A one-shot command bound to a key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// 1 to 9, then 0 (one digit for each of the first ten methods of
    /// `METHOD_NAMES`), and ` (the key left of 1) for `auto`: the method at
    /// this index.
    Method(usize),
    /// M: the next method.
    NextMethod,
    /// H: the other hierarchy (bvh / kdtree), rebuilt.
    ToggleHierarchy,
    /// V: query boxes coloured by result (the CHC paper's Figure 4).
    ToggleBoxes,
    /// L: of the GPU-driven methods' box tests, the next one alone (for
    /// `ioc`, the next level), then all again.
    NextBoxTest,
    /// Z: boxes coloured by the depth-pyramid level they were tested at
    /// (`hiz`), or by outcome again; turns the boxes on.
    TogglePyramidLevels,
    /// P: play or stop the scene's walkthrough.
    TogglePlayback,
    /// R: start recording a camera path, or stop and write it.
    ToggleRecording,
    /// Escape: close the viewer.
    Quit,
}

/// The command bound to `key`, if any.
pub fn action(key: KeyCode) -> Option<Action> {
    const DIGITS: [KeyCode; 10] = [
        KeyCode::Digit1,
        KeyCode::Digit2,
        KeyCode::Digit3,
        KeyCode::Digit4,
        KeyCode::Digit5,
        KeyCode::Digit6,
        KeyCode::Digit7,
        KeyCode::Digit8,
        KeyCode::Digit9,
        KeyCode::Digit0,
    ];
    if let Some(i) = DIGITS.iter().take(METHOD_NAMES.len()).position(|&d| d == key) {
        return Some(Action::Method(i));
    }
    Some(match key {
        KeyCode::Backquote => Action::Method(METHOD_NAMES.iter().position(|&m| m == "auto")?),
        KeyCode::KeyM => Action::NextMethod,
        KeyCode::KeyH => Action::ToggleHierarchy,
        KeyCode::KeyV => Action::ToggleBoxes,
        KeyCode::KeyL => Action::NextBoxTest,
        KeyCode::KeyZ => Action::TogglePyramidLevels,
        KeyCode::KeyP => Action::TogglePlayback,
        KeyCode::KeyR => Action::ToggleRecording,
        KeyCode::Escape => Action::Quit,
        _ => return None,
    })
}

/// The keys held down now.
#[derive(Clone, Debug, Default)]
pub struct HeldKeys(HashSet<KeyCode>);

impl HeldKeys {
    /// Notes a key going down (`true`) or up.
    pub fn set(&mut self, key: KeyCode, down: bool) {
        if down {
            self.0.insert(key);
        } else {
            self.0.remove(&key);
        }
    }

    /// Forgets every key (the window lost focus and will not see them go up).
    pub fn clear(&mut self) {
        self.0.clear();
    }

    /// Where the held keys push the fly camera: W/S forward and back, A/D
    /// left and right, E or Space up, Q or Ctrl down, Shift faster.
    pub fn movement(&self) -> Movement {
        let held = |keys: &[KeyCode]| keys.iter().any(|k| self.0.contains(k));
        let axis =
            |plus: &[KeyCode], minus: &[KeyCode]| f32::from(u8::from(held(plus))) - f32::from(u8::from(held(minus)));
        Movement {
            forward: axis(&[KeyCode::KeyW, KeyCode::ArrowUp], &[KeyCode::KeyS, KeyCode::ArrowDown]),
            right: axis(&[KeyCode::KeyD, KeyCode::ArrowRight], &[KeyCode::KeyA, KeyCode::ArrowLeft]),
            up: axis(&[KeyCode::KeyE, KeyCode::Space], &[KeyCode::KeyQ, KeyCode::ControlLeft, KeyCode::ControlRight]),
            fast: held(&[KeyCode::ShiftLeft, KeyCode::ShiftRight]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_map_to_actions_and_movement() {
        assert_eq!(action(KeyCode::Digit4), Some(Action::Method(3)));
        // Every method has a digit, 0 the tenth (roc, ioc, hiz and moc are 6 to 9).
        assert_eq!(METHOD_NAMES[5..9], ["roc", "ioc", "hiz", "moc"]);
        assert_eq!(action(KeyCode::Digit7), Some(Action::Method(6)));
        assert_eq!(action(KeyCode::Digit8), Some(Action::Method(7)));
        assert_eq!(action(KeyCode::Digit9), Some(Action::Method(8)));
        assert_eq!(action(KeyCode::Digit0), Some(Action::Method(9)));
        assert_eq!(
            action(KeyCode::Backquote).map(|a| matches!(a, Action::Method(i) if METHOD_NAMES[i] == "auto")),
            Some(true)
        );
        assert_eq!(action(KeyCode::KeyV), Some(Action::ToggleBoxes));
        assert_eq!(action(KeyCode::KeyL), Some(Action::NextBoxTest));
        assert_eq!(action(KeyCode::KeyZ), Some(Action::TogglePyramidLevels));
        assert_eq!(action(KeyCode::KeyW), None);
        let mut held = HeldKeys::default();
        held.set(KeyCode::KeyW, true);
        held.set(KeyCode::KeyA, true);
        held.set(KeyCode::ShiftLeft, true);
        held.set(KeyCode::Space, true);
        held.set(KeyCode::KeyQ, true);
        assert_eq!(held.movement(), Movement { forward: 1.0, right: -1.0, up: 0.0, fast: true });
        held.set(KeyCode::KeyW, false);
        assert_eq!(held.movement().forward, 0.0);
        held.clear();
        assert_eq!(held.movement(), Movement::default());
    }
}
