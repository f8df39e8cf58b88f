// The line atop every builder page: the five builders and the instructor
// console, each link carrying the page's token, the page's own marked.
import { token } from './common.js';

export const BUILDER_PAGES = [['Console', 'console_builder.html'], ['Robot', 'robot_builder.html'],
  ['World', 'world_builder.html'], ['Task', 'task_builder.html'], ['Training', 'training.html']];

// Fills `box` (the page's <nav id="builders">); `current` is the page's file.
export function drawBuilderNav(box, current) {
  const q = '?token=' + encodeURIComponent(token);
  const link = (label, page) => {
    const a = document.createElement('a');
    a.href = page + q;
    a.textContent = label;
    if (page === current) a.className = 'current';
    return a;
  };
  box.replaceChildren('builders: ', ...BUILDER_PAGES.flatMap(([label, page], i) => [i ? ' · ' : '', link(label, page)]),
    ' · ', link('instructor console', '/'));
}
