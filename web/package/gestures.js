// What pointers on a viewer's canvas ask of its camera, told apart by pointer id: one pointer drags
// (the primary button orbits, the others pan); two pinch to dolly and move together to pan; more
// are ignored until they lift. Pure: the viewer feeds it pointer events and applies the actions.

// A dolly step scales the distance to the target by 0.9 (the viewer's camera, camera.rs): fingers
// spreading by 1/0.9 are one step closer.
export const PINCH_PER_STEP = -Math.log(0.9);

export class Gestures {
  #pointers = new Map();

  /// A pointer went down at (x, y) CSS pixels with `button` (0: the primary).
  down(id, x, y, button) {
    this.#pointers.set(id, { x, y, pan: button !== 0 });
  }

  /// Pointer `id` moved to (x, y): the camera's moves, each `{ drag: [dx, dy, pan] }` or
  /// `{ dolly: steps }`; none for a pointer that is not down.
  move(id, x, y) {
    const was = this.#pointers.get(id);
    if (!was) return [];
    const now = { ...was, x, y };
    this.#pointers.set(id, now);
    if (this.#pointers.size === 1) return [{ drag: [now.x - was.x, now.y - was.y, was.pan] }];
    if (this.#pointers.size !== 2) return [];
    const [other] = [...this.#pointers].filter(([key]) => key !== id).map(([, p]) => p);
    const before = Math.hypot(was.x - other.x, was.y - other.y);
    const after = Math.hypot(now.x - other.x, now.y - other.y);
    const actions = [];
    if (before > 0 && after > 0 && after !== before) actions.push({ dolly: Math.log(after / before) / PINCH_PER_STEP });
    // The two fingers' midpoint moves by half of this one's move.
    if (now.x !== was.x || now.y !== was.y) actions.push({ drag: [(now.x - was.x) / 2, (now.y - was.y) / 2, true] });
    return actions;
  }

  /// Pointer `id` lifted, was cancelled or lost its capture.
  release(id) {
    this.#pointers.delete(id);
  }

  /// How many pointers are down.
  get count() {
    return this.#pointers.size;
  }
}
