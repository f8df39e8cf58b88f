// The robot's sounds in WebAudio: every SoundCue rise-sim publishes
// (msgs/lcmtypes/SoundCue.lcm), synthesised — no samples are shipped. A cue's
// `sample` names a voice (the robot files' wheel_motor_whine, plastic_impact,
// door_creak, ...); a name without a voice gets the generic one.
// Continuous cues hold a level until the next message: their gain and pitch
// glide there (setTargetAtTime); gain 0 fades the voice out. One-shots play
// at once, scaled by their gain, transposed by their pitch.

// How fast a continuous voice follows its cues: rise-sim sends them at the
// RobotState rate (20 ms apart), so a 30 ms time constant glides between
// steps without lagging behind the drive.
const GLIDE_S = 0.03;

// Continuous voices: oscillators [wave, Hz at pitch 1, level] summed through one filter.
const CONTINUOUS = {
  wheel_motor_whine: { waves: [['sawtooth', 320, 0.5], ['triangle', 640, 0.3]], filter: ['lowpass', 2400] },
  tracked_motor_hum: { waves: [['sawtooth', 70, 0.6], ['square', 140, 0.25]], filter: ['lowpass', 700] },
  servo_whine: { waves: [['square', 700, 0.25], ['sawtooth', 1400, 0.2]], filter: ['bandpass', 1200] },
  servo_small: { waves: [['square', 1100, 0.25]], filter: ['bandpass', 1800] },
  generic: { waves: [['sawtooth', 200, 0.5]], filter: ['lowpass', 1500] },
};

// One-shots: (player, gain, pitch, destination) → plays now.
const ONE_SHOTS = {
  plastic_impact: (p, g, k, out) => { p.noiseBurst(out, g, 'bandpass', 1500 * k, 0.002, 0.12); p.tone(out, g * 0.6, 'sine', 160 * k, 0.002, 0.08); },
  metal_impact: (p, g, k, out) => { for (const [f, l] of [[520, 0.5], [1310, 0.3], [2230, 0.2]]) p.tone(out, g * l, 'sine', f * k, 0.001, 0.7); p.noiseBurst(out, g * 0.4, 'highpass', 2500, 0.001, 0.03); },
  metal_snap: (p, g, k, out) => { p.noiseBurst(out, g, 'highpass', 3000 * k, 0.001, 0.05); p.tone(out, g * 0.5, 'sine', 2400 * k, 0.001, 0.1); },
  door_creak: (p, g, k, out) => p.creak(out, g, k),
  crash: (p, g, k, out) => { p.noiseBurst(out, g, 'lowpass', 1200 * k, 0.003, 0.8); p.tone(out, g * 0.7, 'sine', 60 * k, 0.003, 0.5); },
  heavy_crash: (p, g, k, out) => { p.noiseBurst(out, g, 'lowpass', 700 * k, 0.004, 1.4); p.tone(out, g * 0.8, 'sine', 45 * k, 0.004, 0.9); },
  horn: (p, g, k, out) => { p.tone(out, g * 0.5, 'square', 415 * k, 0.01, 0.5, true); p.tone(out, g * 0.5, 'square', 520 * k, 0.01, 0.5, true); },
  generic: (p, g, k, out) => p.tone(out, g, 'sine', 660 * k, 0.005, 0.25),
};

export function voiceName(sample, continuous) {
  return Object.hasOwn(continuous ? CONTINUOUS : ONE_SHOTS, sample) ? sample : 'generic';
}

export class SoundPlayer {
  // Everything goes through one master gain and an AnalyserNode (the level
  // the page shows and the tests read) to `destination`.
  constructor(ctx, destination = ctx.destination) {
    this.ctx = ctx;
    this.master = ctx.createGain(); this.master.gain.value = 0.8;
    this.analyser = ctx.createAnalyser(); this.analyser.fftSize = 2048;
    this.master.connect(this.analyser); this.analyser.connect(destination);
    this.voices = new Map();  // continuous cue name → {gain, oscillators, base}
    this.held = {};           // continuous cue name → {gain, pitch} last set
    this.oneShots = 0;
    const n = ctx.sampleRate;  // one second of white noise for the bursts
    this.noise = ctx.createBuffer(1, n, n);
    const d = this.noise.getChannelData(0);
    for (let i = 0; i < n; ++i) d[i] = Math.random() * 2 - 1;
  }

  cue(c) {
    if (c.continuous) this.hold(c.name, c.sample, c.gain, c.pitch);
    else this.play(c.sample, c.gain, c.pitch);
  }

  // A continuous cue: its voice glides to gain and pitch.
  hold(name, sample, gain, pitch) {
    let v = this.voices.get(name);
    if (!v) {
      if (gain <= 0) return;  // a silent cue needs no voice yet
      v = this.continuousVoice(CONTINUOUS[voiceName(sample, true)]);
      this.voices.set(name, v);
    }
    const t = this.ctx.currentTime;
    v.gain.gain.setTargetAtTime(Math.max(0, gain), t, GLIDE_S);
    for (const o of v.oscillators) o.frequency.setTargetAtTime(o.base * Math.max(0.05, pitch), t, GLIDE_S);
    this.held[name] = { gain, pitch, voice: voiceName(sample, true) };
  }

  continuousVoice(spec) {
    const gain = this.ctx.createGain(); gain.gain.value = 0;
    const filter = this.ctx.createBiquadFilter(); filter.type = spec.filter[0]; filter.frequency.value = spec.filter[1];
    filter.connect(gain); gain.connect(this.master);
    const oscillators = spec.waves.map(([type, hz, level]) => {
      const o = this.ctx.createOscillator(); o.type = type; o.frequency.value = hz; o.base = hz;
      const l = this.ctx.createGain(); l.gain.value = level;
      o.connect(l); l.connect(filter); o.start();
      return o;
    });
    return { gain, oscillators };
  }

  // A one-shot, now.
  play(sample, gain, pitch) {
    if (!(gain > 0)) return;
    ++this.oneShots;
    ONE_SHOTS[voiceName(sample, false)](this, gain, Math.max(0.05, pitch || 1), this.master);
  }

  // An envelope: up to `level` in `attack` s, then down over `decay` s
  // (exponentially; `flat`: held, then a short release).
  envelope(level, attack, decay, flat = false) {
    const g = this.ctx.createGain(), t = this.ctx.currentTime;
    g.gain.setValueAtTime(0, t);
    g.gain.linearRampToValueAtTime(level, t + attack);
    if (flat) { g.gain.setValueAtTime(level, t + decay); g.gain.linearRampToValueAtTime(0, t + decay + 0.02); }
    else g.gain.setTargetAtTime(0, t + attack, decay / 4);
    return g;
  }

  tone(out, level, type, hz, attack, decay, flat = false) {
    const o = this.ctx.createOscillator(); o.type = type; o.frequency.value = hz;
    const env = this.envelope(level, attack, decay, flat);
    o.connect(env); env.connect(out);
    o.start(); o.stop(this.ctx.currentTime + attack + decay + 0.05);
  }

  noiseBurst(out, level, filterType, hz, attack, decay) {
    const s = this.ctx.createBufferSource(); s.buffer = this.noise;
    const f = this.ctx.createBiquadFilter(); f.type = filterType; f.frequency.value = hz;
    const env = this.envelope(level, attack, decay);
    s.connect(f); f.connect(env); env.connect(out);
    s.start(); s.stop(this.ctx.currentTime + Math.min(1, attack + decay + 0.05));
  }

  // A creaking hinge: a low sawtooth whose pitch wobbles, through a resonance.
  creak(out, level, k) {
    const t = this.ctx.currentTime;
    const o = this.ctx.createOscillator(); o.type = 'sawtooth'; o.frequency.value = 110 * k;
    const lfo = this.ctx.createOscillator(); lfo.frequency.value = 9;
    const depth = this.ctx.createGain(); depth.gain.value = 30 * k;
    lfo.connect(depth); depth.connect(o.frequency);
    const f = this.ctx.createBiquadFilter(); f.type = 'bandpass'; f.frequency.value = 900 * k; f.Q.value = 4;
    const env = this.envelope(level, 0.05, 0.9, true);
    o.connect(f); f.connect(env); env.connect(out);
    for (const x of [o, lfo]) { x.start(t); x.stop(t + 1.0); }
  }

  // The output's RMS over the analyser's last 2048 samples (0..1).
  level() {
    const d = new Float32Array(this.analyser.fftSize);
    this.analyser.getFloatTimeDomainData(d);
    let s = 0;
    for (const x of d) s += x * x;
    return Math.sqrt(s / d.length);
  }
}
