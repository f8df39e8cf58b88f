// The instructor's progress list: a run of the same event (a collision that
// goes on sends collision_continues each second per touching part, and the
// trainer a penalty with each) folds into one line with a count and the time
// it spans. Pure, for the console page and its node test.

// A run ends after this long without its event (collision_continues comes every second).
export const QUIET_GAP_S = 3;

// What folds: the same trainee's same event, in its own stream (SimEvents and
// TaskEvents interleave, each folds on its own).
export function foldKey(e) {
  return e.trainee + '|' + e.channel_kind + '|' + (e.channel_kind === 'task_event' ? e.name : e.kind);
}

function stream(e) { return e.trainee + '|' + e.channel_kind; }

// Adds event `e` (as the SSE stream carries it: utime in µs, channel_kind,
// trainee) to `lines` (oldest first) and returns the line it went into. It
// joins the newest line of its stream when that line has its key and its
// last event is at most `gapS` earlier; anything else starts a line.
export function foldEvent(lines, e, gapS = QUIET_GAP_S) {
  const key = foldKey(e), s = stream(e);
  let last = null;
  for (let i = lines.length - 1; i >= 0 && !last; i--) if (lines[i].stream === s) last = lines[i];
  if (last && last.key === key && (e.utime - last.lastUtime) / 1e6 <= gapS) {
    last.count++;
    last.lastUtime = e.utime;
    last.last = e;
    if (e.channel_kind === 'sim_event') last.parties.add(parties(e));
    return last;
  }
  const line = { key, stream: s, count: 1, firstUtime: e.utime, lastUtime: e.utime, first: e, last: e,
                 parties: new Set(e.channel_kind === 'sim_event' ? [parties(e)] : []) };
  lines.push(line);
  return line;
}

// Folds a whole list of events (oldest first) into lines.
export function foldEvents(events, gapS = QUIET_GAP_S) {
  const lines = [];
  for (const e of events) foldEvent(lines, e, gapS);
  return lines;
}

function parties(e) { return e.a + (e.b ? ' / ' + e.b : ''); }

// One line's text: the event as before, and for a run "×N over T s".
export function lineText(line) {
  const e = line.last, run = line.count > 1
    ? ' ×' + line.count + ' over ' + ((line.lastUtime - line.firstUtime) / 1e6).toFixed(1) + ' s' : '';
  if (e.channel_kind === 'task_event')
    return e.trainee + ' task ' + e.name + ' ' + (e.points >= 0 ? '+' : '') + e.points + run + ' → ' + e.score;
  return e.trainee + ' ' + e.kind + run + ' ' + [...line.parties].join(', ') + (e.detail ? ' (' + e.detail + ')' : '');
}
