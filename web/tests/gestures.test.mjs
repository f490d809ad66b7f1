// The package's pointer gestures (web/package/gestures.js), without a browser: pointers told apart
// by id, one drags (orbit, or pan with another button), two pinch to dolly and pan by their
// midpoint, a third is ignored, and a released or cancelled one moves nothing.
import { test } from "node:test";
import assert from "node:assert/strict";
import { Gestures, PINCH_PER_STEP } from "../package/gestures.js";

test("one pointer orbits with the primary button and pans with the others", () => {
  const g = new Gestures();
  g.down(7, 10, 10, 0);
  assert.deepEqual(g.move(7, 13, 6), [{ drag: [3, -4, false] }]);
  assert.deepEqual(g.move(7, 14, 6), [{ drag: [1, 0, false] }], "from where it last was");
  g.release(7);
  assert.deepEqual(g.move(7, 20, 20), [], "a lifted pointer moves nothing");
  g.down(3, 0, 0, 2);
  assert.deepEqual(g.move(3, 5, 0), [{ drag: [5, 0, true] }]);
  assert.deepEqual(g.move(4, 9, 9), [], "a pointer that never went down moves nothing");
});

test("two pointers pinch to dolly and pan by their midpoint; a third waits", () => {
  const g = new Gestures();
  g.down(1, 0, 0, 0);
  g.down(2, 100, 0, 0);
  // Spread from 100 to 100/0.9 pixels apart: one dolly step closer; the midpoint moves by half.
  const [spread, midpoint] = g.move(2, 100 / 0.9, 0);
  assert.ok(Math.abs(spread.dolly - 1) < 1e-9, `dolly ${spread.dolly}`);
  assert.ok(Math.abs(midpoint.drag[0] - 50 * (1 / 0.9 - 1)) < 1e-9 && midpoint.drag[1] === 0 && midpoint.drag[2]);
  // Turning about the other finger at the same distance: a pan, no dolly.
  assert.deepEqual(g.move(2, 0, 100 / 0.9), [{ drag: [-50 / 0.9, 50 / 0.9, true] }]);
  // Pinching in: steps away, by the log of the ratio.
  const [closer] = g.move(2, 0, 50);
  assert.ok(Math.abs(closer.dolly - Math.log(50 / (100 / 0.9)) / PINCH_PER_STEP) < 1e-9 && closer.dolly < 0);
  g.down(9, 300, 300, 0);
  assert.deepEqual(g.move(9, 310, 300), [], "a third pointer moves nothing");
  assert.deepEqual(g.move(1, 0, 0), [], "nor the others while three are down");
  g.release(9);
  g.release(2);
  assert.equal(g.count, 1);
  assert.deepEqual(g.move(1, 3, 4), [{ drag: [3, 4, false] }], "the finger left drags alone");
});
