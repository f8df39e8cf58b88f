// The progress list's folding (instructor/web/src/event_fold.js, the module
// the console page bundles), under node's test runner: a collision that goes
// on folds into one line per stream with its count and span; another event
// kind or a quiet gap ends the run; SimEvents and TaskEvents interleave.
// usage: node --test tests/instructor/event_fold_test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { foldEvents, lineText, QUIET_GAP_S } from '../../instructor/web/src/event_fold.js';

const T0 = 1_700_000_000_000_000;  // µs
const sim = (t, kind, a = 'chassis', b = 'wall_3') =>
  ({ channel_kind: 'sim_event', trainee: 't1', utime: T0 + Math.round(t * 1e6), kind, a, b, detail: '' });
const task = (t, name, points, score) =>
  ({ channel_kind: 'task_event', trainee: 't1', utime: T0 + Math.round(t * 1e6), name, kind: 'penalty', points, score, detail: '' });

// What the yard drill sends while the chassis and a wheel rub a wall: per
// second two collision_continues and the trainer's penalty.
function rubbing(from, seconds, score0) {
  const out = [];
  for (let i = 0; i < seconds; i++) {
    const t = from + i;
    out.push(sim(t, 'collision_continues'), sim(t + 0.01, 'collision_continues', 'wheel_fl'),
             task(t + 0.02, 'collision', -1, score0 - i - 1));
  }
  return out;
}

test('a collision that goes on folds into one line per stream with a count and a span', () => {
  const events = [sim(0, 'collision_started'), ...rubbing(1, 14, 100), sim(14.9, 'collision_stopped')];
  const lines = foldEvents(events);
  assert.deepEqual(lines.map((l) => [l.key.split('|')[2], l.count]),
                   [['collision_started', 1], ['collision_continues', 28], ['collision', 14], ['collision_stopped', 1]]);
  const text = lines.map(lineText);
  assert.equal(text[1], 't1 collision_continues ×28 over 13.0 s chassis / wall_3, wheel_fl / wall_3');
  assert.equal(text[2], 't1 task collision -1 ×14 over 13.0 s → 86');
  assert.equal(text[0], 't1 collision_started chassis / wall_3');
});

test('another event kind in the same stream ends the run', () => {
  const events = [...rubbing(0, 3, 10), sim(3.5, 'region_entered', 'chassis', 'dock'), ...rubbing(4, 2, 7)];
  const counts = foldEvents(events).filter((l) => l.stream === 't1|sim_event').map((l) => l.count);
  assert.deepEqual(counts, [6, 1, 4]);
  // The trainer's penalties saw no other task event: one run across.
  const penalties = foldEvents(events).filter((l) => l.stream === 't1|task_event').map((l) => l.count);
  assert.deepEqual(penalties, [5]);
});

test('a quiet gap ends the run; an event just inside the gap joins it', () => {
  const inside = foldEvents([sim(0, 'collision_continues'), sim(QUIET_GAP_S, 'collision_continues')]);
  assert.equal(inside.length, 1);
  assert.equal(inside[0].count, 2);
  const after = foldEvents([sim(0, 'collision_continues'), sim(QUIET_GAP_S + 0.1, 'collision_continues')]);
  assert.deepEqual(after.map((l) => l.count), [1, 1]);
});

test('trainees fold apart', () => {
  const other = (t) => Object.assign(sim(t, 'collision_continues'), { trainee: 't2' });
  const lines = foldEvents([sim(0, 'collision_continues'), other(0.1), sim(1, 'collision_continues'), other(1.1)]);
  assert.deepEqual(lines.map((l) => [l.first.trainee, l.count]), [['t1', 2], ['t2', 2]]);
  assert.equal(lineText(lines[1]), 't2 collision_continues ×2 over 1.0 s chassis / wall_3');
});
