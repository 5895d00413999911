// The script of a `lagrange report` page.
//
// It reads the `lagrange.report/1` object from the page's
// <script type="application/json" id="lagrange-data"> element and builds everything
// the page shows from it: the mechanism animated on a canvas (with its play, speed,
// scrub and loop controls), the plots with their hover readouts and time markers, the
// audit table and the analyses. One clock (the shown time) drives them all; `render()`
// redraws whatever depends on it.
//
// Where to start: `main()` at the bottom. The parts, in order: reading the data, numbers
// and rows (interpolation), the clock, cameras (2-D fit, 3-D orthographic), drawing the
// mechanism, plots, the audit, the analyses, and the test interface
// `window.lagrangeReport`.
(function () {
  'use strict';

  // ---------------------------------------------------------------------------------------
  // Constants of the look.

  const PALETTE = ['#1f5fd6', '#d6402b', '#2a9d4b', '#8e44ad', '#e08a00', '#16a2b8', '#b5477a', '#6b7a1f'];
  const AXIS_COLOURS = ['#d6402b', '#2a9d4b', '#1f5fd6']; // e1, e2, e3 and x, y, z
  const TRAIL_SECONDS = 3; // how much of the past a trail shows
  const SPEEDS = [0.25, 0.5, 1, 2, 4];
  const DRIFT_MODE_SECONDS = 4; // a mode of frequency 0 replays its drift in this long
  const SHORTEST_MODE_PERIOD = 0.8; // faster modes are slowed down to stay visible
  const TAU = 2 * Math.PI;

  // ---------------------------------------------------------------------------------------
  // Reading the data: every field the page uses gets a value of the expected shape, so the
  // drawing code never has to ask whether an array is there.

  function readData() {
    const element = document.getElementById('lagrange-data');
    let raw = {};
    try {
      raw = JSON.parse(element ? element.textContent : '{}') || {};
    } catch (error) {
      raw = { name: 'unreadable report data', derivation: '' };
    }
    const list = (value) => (Array.isArray(value) ? value : []);
    const objects = (value) => list(value).filter((item) => item !== null && typeof item === 'object');
    const time = list(raw.time).map(Number);
    const points = objects(raw.points).map((p, i) => ({
      name: typeof p.name === 'string' ? p.name : `point ${i + 1}`,
      kind: p.kind || 'particle',
      mass: Number.isFinite(p.mass) ? p.mass : 0,
      x: list(p.x),
      y: list(p.y),
      z: Array.isArray(p.z) ? p.z : null,
    }));
    const validSegment = (s) =>
      Array.isArray(s) && s.length === 2 && s.every((k) => Number.isInteger(k) && k >= -1 && k < points.length);
    const lastTime = time.length ? time[time.length - 1] : 0;
    return {
      name: typeof raw.name === 'string' ? raw.name : '',
      dimension: raw.dimension === 3 ? 3 : 2,
      derivation: typeof raw.derivation === 'string' ? raw.derivation : '',
      until: Number.isFinite(raw.until) && raw.until > 0 ? raw.until : Math.max(lastTime, 0),
      time,
      coordinates: objects(raw.coordinates).map((c) => ({
        name: String(c.name), angle: c.angle === true, q: list(c.q), qd: list(c.qd),
      })),
      invariants: objects(raw.invariants).map((v) => ({
        name: String(v.name), conserved: v.conserved === true, values: list(v.values),
      })),
      constraintForces: objects(raw.constraint_forces).map((f) => ({ name: String(f.name), values: list(f.values) })),
      points,
      bodies: objects(raw.bodies)
        .filter((b) => Number.isInteger(b.point) && b.point >= 0 && b.point < points.length && Array.isArray(b.axes))
        .map((b) => ({
          name: String(b.name), point: b.point, length: Number.isFinite(b.length) && b.length > 0 ? b.length : 1,
          axes: [0, 1, 2].map((k) => list(b.axes[k])),
        })),
      rods: list(raw.rods).filter(validSegment),
      springs: list(raw.springs).filter(validSegment),
      summary: raw.summary && typeof raw.summary === 'object' ? raw.summary : {},
      events: objects(raw.events).filter((e) => e && Number.isFinite(e.t)),
      analyses: raw.analyses && typeof raw.analyses === 'object' ? raw.analyses : {},
    };
  }

  const data = readData();

  // ---------------------------------------------------------------------------------------
  // Numbers and rows.

  /** A number for people: `digits` significant digits, exponent form when very large or small. */
  function fmt(v, digits = 4) {
    if (v === null || v === undefined || Number.isNaN(v)) return '—';
    if (!Number.isFinite(v)) return v > 0 ? '∞' : '−∞';
    if (v === 0) return '0';
    const a = Math.abs(v);
    const text = a >= 1e5 || a < 1e-3
      ? v.toExponential(digits - 1).replace(/\.?0+e/, 'e')
      : String(Number(v.toPrecision(digits)));
    return text.replace('-', '−');
  }

  /** An angle wrapped to (−π, π]. */
  function wrap(v) {
    return v - TAU * Math.ceil((v - Math.PI) / TAU);
  }

  /**
   * Where time t falls among the rows: row i and the fraction f of the way to row i + 1.
   * At a row's time f is 0, so that row is shown exactly; outside the run the nearest end.
   */
  function locate(t) {
    const time = data.time;
    const n = time.length;
    if (n === 0) return null;
    if (!(t > time[0])) return { i: 0, f: 0 };
    if (t >= time[n - 1]) return { i: n - 1, f: 0 };
    let lo = 0;
    let hi = n - 1; // time[lo] <= t < time[hi]
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (time[mid] <= t) lo = mid;
      else hi = mid;
    }
    return { i: lo, f: (t - time[lo]) / (time[lo + 1] - time[lo]) };
  }

  /** The value of a per-row array at a located time (linear between rows). */
  function valueAt(values, at) {
    if (!at || !values) return null;
    const a = values[at.i];
    if (!Number.isFinite(a)) return null;
    if (at.f === 0) return a;
    const b = values[at.i + 1];
    return Number.isFinite(b) ? a + at.f * (b - a) : a;
  }

  /** A point's position [x, y, z] at a located time (z = 0 in 2-D). */
  function pointAt(point, at) {
    return [valueAt(point.x, at), valueAt(point.y, at), point.z ? valueAt(point.z, at) : 0];
  }

  /** Smallest and largest finite values of some arrays, or null if there are none. */
  function extent(arrays) {
    let lo = Infinity;
    let hi = -Infinity;
    for (const values of arrays) {
      for (const v of values) {
        if (Number.isFinite(v)) {
          if (v < lo) lo = v;
          if (v > hi) hi = v;
        }
      }
    }
    return lo <= hi ? [lo, hi] : null;
  }

  // ---------------------------------------------------------------------------------------
  // The clock: the shown time, and whether and how fast it runs.

  const clock = { t: 0, playing: false, speed: 1, loop: true, lastFrame: null, frameRequested: false };

  function play() {
    if (data.until <= 0) return;
    if (clock.t >= data.until) clock.t = 0; // play after the end starts over
    clock.playing = true;
    clock.lastFrame = null;
    requestFrame();
    updateControls();
  }

  function pause() {
    clock.playing = false;
    updateControls();
  }

  function seek(t) {
    const target = Number(t);
    if (!Number.isFinite(target)) return clock.t;
    clock.t = Math.min(Math.max(target, 0), data.until);
    render();
    return clock.t;
  }

  function requestFrame() {
    if (clock.frameRequested) return;
    clock.frameRequested = true;
    requestAnimationFrame(onFrame);
  }

  /** One animation frame: advance the clock by the wall time since the last frame. */
  function onFrame(now) {
    clock.frameRequested = false;
    if (clock.playing) {
      if (clock.lastFrame !== null) {
        const elapsed = Math.min((now - clock.lastFrame) / 1000, 0.1); // a hidden tab must not jump
        clock.t += elapsed * clock.speed;
        if (clock.t >= data.until) {
          if (clock.loop && data.until > 0) clock.t %= data.until;
          else {
            clock.t = data.until;
            clock.playing = false;
          }
        }
      }
      clock.lastFrame = now;
    }
    render(true);
    if (clock.playing) requestFrame();
  }

  // ---------------------------------------------------------------------------------------
  // Cameras. A view maps model positions [x, y, z] to canvas pixels [px, py, depth].

  /** The turnable 3-D camera, shared by every 3-D picture on the page (azimuth, elevation). */
  const camera = { azimuth: (-55 * Math.PI) / 180, elevation: (22 * Math.PI) / 180 };

  /** 2-D: equal scale on both axes, fitted to a box [xmin, xmax] × [ymin, ymax]. */
  function view2D(box, width, height, margin) {
    let [x0, x1, y0, y1] = box;
    // A direction with (almost) no extent, such as a row of masses on a line, gets a
    // sliver of room, so that the other direction sets the scale.
    const size = Math.max(x1 - x0, y1 - y0, 1e-9);
    if (x1 - x0 < size * 1e-3) [x0, x1] = [x0 - size * 1e-3, x1 + size * 1e-3];
    if (y1 - y0 < size * 1e-3) [y0, y1] = [y0 - size * 1e-3, y1 + size * 1e-3];
    const scale = Math.min((width - 2 * margin) / (x1 - x0), (height - 2 * margin) / (y1 - y0));
    const cx = (x0 + x1) / 2;
    const cy = (y0 + y1) / 2;
    return {
      scale,
      project: (p) => [width / 2 + (p[0] - cx) * scale, height / 2 - (p[1] - cy) * scale, 0],
    };
  }

  /** 3-D: an orthographic camera looking at `centre` from the shared azimuth and elevation, z up. */
  function view3D(centre, radius, width, height, margin) {
    const { azimuth: az, elevation: el } = camera;
    const right = [-Math.sin(az), Math.cos(az), 0];
    const up = [-Math.sin(el) * Math.cos(az), -Math.sin(el) * Math.sin(az), Math.cos(el)];
    const toward = [Math.cos(el) * Math.cos(az), Math.cos(el) * Math.sin(az), Math.sin(el)];
    const scale = (Math.min(width, height) / 2 - margin) / Math.max(radius, 1e-9);
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    return {
      scale,
      project: (p) => {
        const d = [p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]];
        return [width / 2 + dot(d, right) * scale, height / 2 - dot(d, up) * scale, dot(d, toward)];
      },
    };
  }

  /** The room a set of positions needs: a 2-D box, or a 3-D centre and radius. */
  function boundsOf(positions) {
    const xs = extent([positions.map((p) => p[0])]) || [0, 0];
    const ys = extent([positions.map((p) => p[1])]) || [0, 0];
    const zs = extent([positions.map((p) => p[2])]) || [0, 0];
    const centre = [(xs[0] + xs[1]) / 2, (ys[0] + ys[1]) / 2, (zs[0] + zs[1]) / 2];
    let radius = 0;
    for (const p of positions) {
      if (p.every(Number.isFinite)) radius = Math.max(radius, Math.hypot(p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]));
    }
    return { box: [xs[0], xs[1], ys[0], ys[1]], centre, radius: radius || 1 };
  }

  /** A view of `bounds` for a canvas of the given size, 2-D or 3-D as the model is. */
  function viewFor(bounds, width, height, margin) {
    return data.dimension === 3
      ? view3D(bounds.centre, bounds.radius, width, height, margin)
      : view2D(bounds.box, width, height, margin);
  }

  /** Lets the user turn the 3-D camera by dragging on a canvas. */
  function makeTurnable(canvas) {
    if (data.dimension !== 3) return;
    canvas.classList.add('turnable');
    let last = null;
    canvas.addEventListener('pointerdown', (event) => {
      last = [event.clientX, event.clientY];
      canvas.setPointerCapture(event.pointerId);
      canvas.classList.add('turning');
    });
    canvas.addEventListener('pointermove', (event) => {
      if (!last) return;
      camera.azimuth -= (event.clientX - last[0]) * 0.01;
      const limit = Math.PI / 2 - 0.01;
      camera.elevation = Math.min(limit, Math.max(-limit, camera.elevation + (event.clientY - last[1]) * 0.01));
      last = [event.clientX, event.clientY];
      render();
    });
    const stop = () => {
      last = null;
      canvas.classList.remove('turning');
    };
    canvas.addEventListener('pointerup', stop);
    canvas.addEventListener('pointercancel', stop);
  }

  /** Sizes a canvas's pixel buffer to its CSS box (sharp on high-density screens). */
  function fitCanvas(canvas) {
    const box = canvas.getBoundingClientRect();
    const ratio = window.devicePixelRatio || 1;
    const width = Math.max(1, Math.round(box.width));
    const height = Math.max(1, Math.round(box.height));
    canvas.width = Math.round(width * ratio);
    canvas.height = Math.round(height * ratio);
    const context = canvas.getContext('2d');
    context.setTransform(ratio, 0, 0, ratio, 0, 0);
    return { context, width, height };
  }

  // ---------------------------------------------------------------------------------------
  // Drawing the mechanism: rods, springs, pivots, body axes and discs, in model positions
  // given per point.

  const maxMass = Math.max(0, ...data.points.map((p) => p.mass));

  /** A disc's radius in pixels: area proportional to mass, never too small to see. */
  function discRadius(mass, base) {
    if (!(maxMass > 0) || !(mass > 0)) return Math.max(3, base * 0.35);
    return Math.max(3, base * Math.sqrt(mass / maxMass));
  }

  function drawLine(context, a, b, colour, width, dash) {
    context.save();
    context.strokeStyle = colour;
    context.lineWidth = width;
    if (dash) context.setLineDash(dash);
    context.beginPath();
    context.moveTo(a[0], a[1]);
    context.lineTo(b[0], b[1]);
    context.stroke();
    context.restore();
  }

  /** A spring as a zig-zag between two canvas points, straight for a short bit at each end. */
  function drawSpring(context, a, b, colour) {
    const dx = b[0] - a[0];
    const dy = b[1] - a[1];
    const length = Math.hypot(dx, dy);
    if (length < 1) return;
    const [ux, uy] = [dx / length, dy / length];
    const [nx, ny] = [-uy, ux];
    const turns = 12;
    const amplitude = Math.min(7, length / 6);
    context.save();
    context.strokeStyle = colour;
    context.lineWidth = 1.6;
    context.lineJoin = 'round';
    context.beginPath();
    context.moveTo(a[0], a[1]);
    const start = 0.12 * length;
    const coil = 0.76 * length;
    context.lineTo(a[0] + ux * start, a[1] + uy * start);
    for (let k = 0; k < turns; k++) {
      const s = start + ((k + 0.5) / turns) * coil;
      const side = k % 2 === 0 ? amplitude : -amplitude;
      context.lineTo(a[0] + ux * s + nx * side, a[1] + uy * s + ny * side);
    }
    context.lineTo(a[0] + ux * (start + coil), a[1] + uy * (start + coil));
    context.lineTo(b[0], b[1]);
    context.stroke();
    context.restore();
  }

  /** The fixed origin that rods and springs hang from: a small hatched mount. */
  function drawPivot(context, at) {
    context.save();
    context.strokeStyle = '#3b4252';
    context.fillStyle = '#3b4252';
    context.lineWidth = 1.2;
    context.beginPath();
    context.moveTo(at[0] - 12, at[1] - 7);
    context.lineTo(at[0] + 12, at[1] - 7);
    context.stroke();
    for (let k = -12; k < 12; k += 4) {
      context.beginPath();
      context.moveTo(at[0] + k, at[1] - 7);
      context.lineTo(at[0] + k + 4, at[1] - 12);
      context.stroke();
    }
    context.beginPath();
    context.arc(at[0], at[1], 3.5, 0, TAU);
    context.fill();
    context.restore();
  }

  function drawDisc(context, at, radius, colour, label) {
    context.save();
    context.fillStyle = colour;
    context.strokeStyle = '#ffffff';
    context.lineWidth = 1.5;
    context.beginPath();
    context.arc(at[0], at[1], radius, 0, TAU);
    context.fill();
    context.stroke();
    if (label) {
      context.fillStyle = '#3b4252';
      context.font = '11px system-ui, sans-serif';
      context.fillText(label, at[0] + radius + 3, at[1] - radius - 1);
    }
    context.restore();
  }

  /** Faint x, y, z axes through the origin of a 3-D picture, with their names. */
  function drawSpaceAxes(context, view, length) {
    ['x', 'y', 'z'].forEach((name, k) => {
      const tip = [0, 0, 0];
      tip[k] = length;
      const a = view.project([0, 0, 0]);
      const b = view.project(tip);
      drawLine(context, a, b, AXIS_COLOURS[k] + '88', 1.2);
      context.save();
      context.fillStyle = AXIS_COLOURS[k];
      context.font = '12px system-ui, sans-serif';
      context.fillText(name, b[0] + 3, b[1] - 3);
      context.restore();
    });
  }

  /**
   * The mechanism in one configuration: `positions` holds [x, y, z] per point (null where
   * unknown), `axes` per body its three unit vectors (or null). Discs are drawn last,
   * far ones first.
   */
  function drawMechanism(context, view, positions, axes, base, labels) {
    const origin = view.project([0, 0, 0]);
    const screen = positions.map((p) => (p && p.every(Number.isFinite) ? view.project(p) : null));
    const end = (k) => (k === -1 ? origin : screen[k]);
    let pivot = false;
    for (const [a, b] of data.rods) {
      if (a === -1 || b === -1) pivot = true;
      if (end(a) && end(b)) drawLine(context, end(a), end(b), '#4c566a', 2.5);
    }
    for (const [a, b] of data.springs) {
      if (a === -1 || b === -1) pivot = true;
      if (end(a) && end(b)) drawSpring(context, end(a), end(b), '#4c566a');
    }
    if (pivot) drawPivot(context, origin);
    data.bodies.forEach((body, j) => {
      const at = positions[body.point];
      if (!axes || !axes[j] || !at || !at.every(Number.isFinite)) return;
      axes[j].forEach((e, k) => {
        if (!e) return;
        const tip = [at[0] + e[0] * body.length, at[1] + e[1] * body.length, at[2] + e[2] * body.length];
        const from = view.project(at);
        const to = view.project(tip);
        drawLine(context, from, to, AXIS_COLOURS[k], k === 2 ? 3.5 : 2.2);
        context.save();
        context.fillStyle = AXIS_COLOURS[k];
        context.font = '12px system-ui, sans-serif';
        context.fillText(`e${k + 1}`, to[0] + 4, to[1] - 4);
        context.restore();
      });
    });
    const order = screen.map((s, i) => i).filter((i) => screen[i]);
    order.sort((i, j) => screen[i][2] - screen[j][2]);
    for (const i of order) {
      const point = data.points[i];
      drawDisc(context, screen[i], discRadius(point.mass, base), PALETTE[i % PALETTE.length], labels ? point.name : '');
    }
  }

  // ---------------------------------------------------------------------------------------
  // The main stage: the mechanism at the shown time, with trails.

  const stage = { canvas: null, context: null, width: 0, height: 0, bounds: null };

  /** Every place the mechanism reaches during the run, to fit the view once for the whole run. */
  function mechanismBounds() {
    const places = [];
    const usesOrigin = [...data.rods, ...data.springs].some(([a, b]) => a === -1 || b === -1);
    if (usesOrigin || data.dimension === 3) places.push([0, 0, 0]);
    for (const point of data.points) {
      for (let i = 0; i < point.x.length; i++) places.push([point.x[i], point.y[i], point.z ? point.z[i] : 0]);
    }
    const bounds = boundsOf(places);
    // A body's axes reach `length` from its reference point in any direction.
    for (const body of data.bodies) {
      const point = data.points[body.point];
      for (let i = 0; i < point.x.length; i++) {
        const p = [point.x[i], point.y[i], point.z ? point.z[i] : 0];
        if (!p.every(Number.isFinite)) continue;
        const reach = Math.hypot(p[0] - bounds.centre[0], p[1] - bounds.centre[1], p[2] - bounds.centre[2]) + body.length;
        bounds.radius = Math.max(bounds.radius, reach);
        bounds.box = [
          Math.min(bounds.box[0], p[0] - body.length), Math.max(bounds.box[1], p[0] + body.length),
          Math.min(bounds.box[2], p[1] - body.length), Math.max(bounds.box[3], p[1] + body.length),
        ];
      }
    }
    return bounds;
  }

  /** The bodies' axes at a located time, normalised (interpolation shortens them slightly). */
  function axesAt(at) {
    return data.bodies.map((body) =>
      body.axes.map((rows) => {
        if (!at || !rows[at.i]) return null;
        const a = rows[at.i];
        const b = at.f === 0 || !rows[at.i + 1] ? a : rows[at.i + 1];
        const v = [0, 1, 2].map((k) => a[k] + at.f * (b[k] - a[k]));
        const n = Math.hypot(v[0], v[1], v[2]);
        return n > 0 && Number.isFinite(n) ? v.map((c) => c / n) : null;
      }),
    );
  }

  /**
   * A fading line along a path over the last TRAIL_SECONDS: `place(i)` is the position at
   * row i, `now` the position at the shown time.
   */
  function drawTrail(context, view, at, colour, place, now) {
    const time = data.time;
    const since = clock.t - TRAIL_SECONDS;
    let previous = now;
    context.save();
    context.strokeStyle = colour;
    context.lineWidth = 1.6;
    for (let i = at.i; i >= 0 && time[i] >= since; i--) {
      const here = place(i);
      if (here.every(Number.isFinite) && previous.every(Number.isFinite)) {
        context.globalAlpha = 0.55 * Math.max(0, 1 - (clock.t - time[i]) / TRAIL_SECONDS);
        const a = view.project(previous);
        const b = view.project(here);
        context.beginPath();
        context.moveTo(a[0], a[1]);
        context.lineTo(b[0], b[1]);
        context.stroke();
      }
      previous = here;
    }
    context.restore();
  }

  /** Trails of the points, and of the tips of the bodies' figure axes e3 (a top's nutation). */
  function drawTrails(context, view, at, axes) {
    if (!at) return;
    data.points.forEach((point, p) => {
      const place = (i) => [point.x[i], point.y[i], point.z ? point.z[i] : 0];
      drawTrail(context, view, at, PALETTE[p % PALETTE.length], place, pointAt(point, at));
    });
    data.bodies.forEach((body, j) => {
      const point = data.points[body.point];
      const e3 = body.axes[2];
      const tip = (p, e) => (e ? [0, 1, 2].map((k) => p[k] + body.length * e[k]) : [NaN, NaN, NaN]);
      const place = (i) => tip([point.x[i], point.y[i], point.z ? point.z[i] : 0], e3[i]);
      drawTrail(context, view, at, AXIS_COLOURS[2], place, tip(pointAt(point, at), axes[j][2]));
    });
  }

  /** A faint cross at the origin of a 2-D picture, when it is in the picture: the fixed reference. */
  function drawOriginMark(context, at, width, height) {
    if (at[0] < 0 || at[0] > width || at[1] < 0 || at[1] > height) return;
    drawLine(context, [at[0] - 6, at[1]], [at[0] + 6, at[1]], '#9aa2b1', 1);
    drawLine(context, [at[0], at[1] - 6], [at[0], at[1] + 6], '#9aa2b1', 1);
  }

  function layoutStage() {
    const fitted = fitCanvas(stage.canvas);
    Object.assign(stage, fitted);
  }

  function drawStage() {
    const { context, width, height } = stage;
    context.clearRect(0, 0, width, height);
    const base = Math.min(16, Math.max(7, Math.min(width, height) / 30));
    const view = viewFor(stage.bounds, width, height, base + 24);
    if (data.dimension === 3) drawSpaceAxes(context, view, stage.bounds.radius * 0.85);
    else drawOriginMark(context, view.project([0, 0, 0]), width, height);
    const at = locate(clock.t);
    const axes = axesAt(at);
    drawTrails(context, view, at, axes);
    const positions = at ? data.points.map((point) => pointAt(point, at)) : [];
    drawMechanism(context, view, positions, axes, base, data.points.length <= 6);
    context.save();
    context.fillStyle = '#3b4252';
    context.font = '13px ui-monospace, Menlo, Consolas, monospace';
    context.fillText(`t = ${clock.t.toFixed(3)}`, 12, 20);
    if (data.dimension === 3) {
      context.fillStyle = '#7b8496';
      context.font = '12px system-ui, sans-serif';
      context.fillText('drag to turn', 12, height - 10);
    }
    context.restore();
  }

  // ---------------------------------------------------------------------------------------
  // The controls under the stage.

  const controls = {};

  function setUpControls() {
    controls.play = document.getElementById('play');
    controls.speed = document.getElementById('speed');
    controls.scrub = document.getElementById('scrub');
    controls.loop = document.getElementById('loop');
    controls.clock = document.getElementById('clock');
    controls.scrub.max = String(data.until);
    controls.play.addEventListener('click', () => (clock.playing ? pause() : play()));
    controls.speed.addEventListener('change', () => {
      const speed = Number(controls.speed.value);
      clock.speed = SPEEDS.includes(speed) ? speed : 1;
    });
    controls.scrub.addEventListener('input', () => seek(Number(controls.scrub.value)));
    controls.loop.addEventListener('change', () => (clock.loop = controls.loop.checked));
    if (data.until <= 0) [controls.play, controls.scrub].forEach((c) => (c.disabled = true));
    showEvents();
  }

  /** The run's events as buttons that seek to them (at most 24, then a count). */
  function showEvents() {
    const holder = document.getElementById('events');
    if (!data.events.length) return;
    holder.hidden = false;
    holder.append('events: ');
    for (const event of data.events.slice(0, 24)) {
      const button = document.createElement('button');
      button.type = 'button';
      button.textContent = `${event.label || 'event'} at t = ${fmt(event.t, 6)}`;
      button.addEventListener('click', () => {
        pause();
        seek(event.t);
      });
      holder.append(button);
    }
    if (data.events.length > 24) holder.append(`… and ${data.events.length - 24} more`);
  }

  function updateControls() {
    if (!controls.play) return;
    controls.play.textContent = clock.playing ? 'Pause' : 'Play';
    controls.scrub.value = String(clock.t);
    controls.clock.value = `t = ${clock.t.toFixed(3)}`;
  }

  // ---------------------------------------------------------------------------------------
  // Plots: curves on a canvas with axes, a marker at the shown time, and a hover readout.
  //
  // A plot is described by a spec: `title`, `xLabel`, `yLabel`, `series()` returning
  // [{label, colour, xs, ys, dash, breaks}] (called again when the unwrap option changes),
  // `marker(at)` returning the dots and lines to draw at the shown time, and `hover`:
  // 'time' (values at the cursor's t) or 'nearest' (the sample nearest the cursor).

  const plots = [];
  const tooltip = { element: null };

  function makePlot(parent, spec) {
    const figure = document.createElement('figure');
    figure.className = 'plot';
    const canvas = document.createElement('canvas');
    const caption = document.createElement('figcaption');
    figure.append(canvas, caption);
    parent.append(figure);
    const plot = { spec, canvas, caption, cache: null, frame: null, series: [], hover: null };
    canvas.addEventListener('pointermove', (event) => {
      const box = canvas.getBoundingClientRect();
      plot.hover = { x: event.clientX - box.left, y: event.clientY - box.top, clientX: event.clientX, clientY: event.clientY };
      drawPlot(plot);
    });
    canvas.addEventListener('pointerleave', () => {
      plot.hover = null;
      tooltip.element.hidden = true;
      drawPlot(plot);
    });
    plots.push(plot);
    return plot;
  }

  /** Round tick values covering [lo, hi], about `count` of them. */
  function ticks(lo, hi, count) {
    const raw = (hi - lo) / count;
    const power = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * power).find((s) => s >= raw) || raw;
    const values = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) values.push(Math.abs(v) < step * 1e-9 ? 0 : v);
    return { values, step };
  }

  function tickLabel(v, step) {
    if (v === 0) return '0';
    const a = Math.max(Math.abs(v), step);
    if (a >= 1e5 || step < 1e-3) return v.toExponential(Math.max(0, Math.min(3, Math.round(Math.log10(a / step))))).replace('-', '−');
    return v.toFixed(Math.max(0, -Math.floor(Math.log10(step) + 1e-9))).replace('-', '−');
  }

  /** The data ranges of a plot's series, padded, or the spec's own ranges. */
  function plotRanges(spec, series) {
    const xr = spec.xRange || extent(series.map((s) => s.xs)) || [0, 1];
    let yr = spec.yRange || extent(series.map((s) => s.ys)) || [-1, 1];
    if (!spec.yRange) {
      const pad = (yr[1] - yr[0]) * 0.06 || Math.max(Math.abs(yr[0]) * 0.1, 1e-12);
      yr = [yr[0] - pad, yr[1] + pad];
    }
    const x = xr[1] > xr[0] ? xr : [xr[0] - 0.5, xr[0] + 0.5];
    return { x, y: yr };
  }

  /** Draws the axes and curves of a plot into its cache (redrawn only on layout or option change). */
  function layoutPlot(plot) {
    const { context, width, height } = fitCanvas(plot.canvas);
    plot.context = context;
    plot.caption.textContent = typeof plot.spec.title === 'function' ? plot.spec.title() : plot.spec.title;
    plot.canvas.setAttribute('aria-label', plot.caption.textContent);
    plot.series = plot.spec.series();
    const ranges = plotRanges(plot.spec, plot.series);
    const yTicks = ticks(ranges.y[0], ranges.y[1], Math.max(2, Math.floor(height / 45)));
    const xTicks = ticks(ranges.x[0], ranges.x[1], Math.max(2, Math.floor(width / 80)));
    context.font = '11px system-ui, sans-serif';
    const labelWidth = Math.max(...yTicks.values.map((v) => context.measureText(tickLabel(v, yTicks.step)).width), 10);
    const frame = { left: labelWidth + 22, right: width - 10, top: 10, bottom: height - 34, ranges };
    frame.px = (x) => frame.left + ((x - ranges.x[0]) / (ranges.x[1] - ranges.x[0])) * (frame.right - frame.left);
    frame.py = (y) => frame.bottom - ((y - ranges.y[0]) / (ranges.y[1] - ranges.y[0])) * (frame.bottom - frame.top);
    frame.fromPx = (px) => ranges.x[0] + ((px - frame.left) / (frame.right - frame.left)) * (ranges.x[1] - ranges.x[0]);
    plot.frame = frame;

    const cache = document.createElement('canvas');
    cache.width = plot.canvas.width;
    cache.height = plot.canvas.height;
    const c = cache.getContext('2d');
    c.setTransform(context.getTransform());
    c.font = '11px system-ui, sans-serif';
    c.fillStyle = '#5b6475';
    c.strokeStyle = '#eceef2';
    c.lineWidth = 1;
    c.textAlign = 'right';
    c.textBaseline = 'middle';
    for (const v of yTicks.values) {
      const y = frame.py(v);
      if (y < frame.top - 1 || y > frame.bottom + 1) continue;
      c.beginPath();
      c.moveTo(frame.left, y);
      c.lineTo(frame.right, y);
      c.stroke();
      c.fillText(tickLabel(v, yTicks.step), frame.left - 5, y);
    }
    c.textAlign = 'center';
    c.textBaseline = 'top';
    for (const v of xTicks.values) {
      const x = frame.px(v);
      if (x < frame.left - 1 || x > frame.right + 1) continue;
      c.beginPath();
      c.moveTo(x, frame.top);
      c.lineTo(x, frame.bottom);
      c.stroke();
      c.fillText(tickLabel(v, xTicks.step), x, frame.bottom + 4);
    }
    c.strokeStyle = '#9aa2b1';
    c.strokeRect(frame.left, frame.top, frame.right - frame.left, frame.bottom - frame.top);
    c.fillStyle = '#3b4252';
    c.fillText(plot.spec.xLabel, (frame.left + frame.right) / 2, frame.bottom + 19);
    c.save();
    c.translate(11, (frame.top + frame.bottom) / 2);
    c.rotate(-Math.PI / 2);
    c.textBaseline = 'middle';
    c.fillText(plot.spec.yLabel, 0, 0);
    c.restore();

    c.save();
    c.beginPath();
    c.rect(frame.left, frame.top, frame.right - frame.left, frame.bottom - frame.top);
    c.clip();
    for (const s of plot.series) drawCurve(c, frame, s);
    c.restore();
    drawLegend(c, frame, plot.series);
    plot.cache = cache;
    drawPlot(plot);
  }

  /** One curve, broken where a value is missing or where `breaks(a, b)` says (an angle's wrap). */
  function drawCurve(context, frame, s) {
    if (s.dots) {
      // Points, not a curve: a Poincaré section.
      context.save();
      context.fillStyle = s.colour;
      for (let i = 0; i < s.xs.length; i++) {
        if (Number.isFinite(s.xs[i]) && Number.isFinite(s.ys[i])) context.fillRect(frame.px(s.xs[i]) - 1, frame.py(s.ys[i]) - 1, 2, 2);
      }
      context.restore();
      return;
    }
    context.save();
    context.strokeStyle = s.colour;
    context.lineWidth = s.width || 1.4;
    if (s.dash) context.setLineDash(s.dash);
    context.beginPath();
    let drawing = false;
    for (let i = 0; i < s.xs.length; i++) {
      const x = s.xs[i];
      const y = s.ys[i];
      if (!Number.isFinite(x) || !Number.isFinite(y)) {
        drawing = false;
        continue;
      }
      const broken = drawing && s.breaks && s.breaks(s.xs[i - 1], s.ys[i - 1], x, y);
      if (drawing && !broken) context.lineTo(frame.px(x), frame.py(y));
      else context.moveTo(frame.px(x), frame.py(y));
      drawing = true;
    }
    context.stroke();
    context.restore();
  }

  /** Names of the curves in the top right corner, when there is more than one named curve. */
  function drawLegend(context, frame, series) {
    const named = series.filter((s) => s.label && !s.unlisted);
    if (named.length < 2) return;
    context.save();
    context.font = '11px system-ui, sans-serif';
    context.textAlign = 'left';
    context.textBaseline = 'middle';
    const width = Math.max(...named.map((s) => context.measureText(s.label).width)) + 28;
    const x = frame.right - width - 6;
    context.fillStyle = 'rgba(255, 255, 255, 0.85)';
    context.fillRect(x, frame.top + 4, width, named.length * 15 + 6);
    named.forEach((s, k) => {
      const y = frame.top + 12 + k * 15;
      drawLine(context, [x + 4, y], [x + 18, y], s.colour, 2, s.dash);
      context.fillStyle = '#3b4252';
      context.fillText(s.label, x + 22, y);
    });
    context.restore();
  }

  /** The plot's cached curves, the marker at the shown time and the hover readout. */
  function drawPlot(plot) {
    const { context, frame, cache } = plot;
    if (!context || !cache) return;
    context.save();
    context.setTransform(1, 0, 0, 1, 0, 0);
    context.clearRect(0, 0, plot.canvas.width, plot.canvas.height);
    context.drawImage(cache, 0, 0);
    context.restore();
    context.save();
    context.beginPath();
    context.rect(frame.left - 4, frame.top - 4, frame.right - frame.left + 8, frame.bottom - frame.top + 8);
    context.clip();
    const marker = plot.spec.marker ? plot.spec.marker(locate(clock.t)) : {};
    for (const x of marker.lines || []) {
      if (Number.isFinite(x)) drawLine(context, [frame.px(x), frame.top], [frame.px(x), frame.bottom], '#2458c6', 1.2);
    }
    for (const dot of marker.dots || []) {
      if (!Number.isFinite(dot.x) || !Number.isFinite(dot.y)) continue;
      context.fillStyle = dot.colour;
      context.strokeStyle = '#ffffff';
      context.beginPath();
      context.arc(frame.px(dot.x), frame.py(dot.y), 4, 0, TAU);
      context.fill();
      context.stroke();
    }
    context.restore();
    if (plot.hover) showReadout(plot);
  }

  /** Under the cursor: a crosshair and a tooltip with the values there. */
  function showReadout(plot) {
    const { context, frame, hover, series } = plot;
    const inside = hover.x >= frame.left && hover.x <= frame.right && hover.y >= frame.top && hover.y <= frame.bottom;
    if (!inside || !series.length) {
      tooltip.element.hidden = true;
      return;
    }
    let lines = [];
    if (plot.spec.hover === 'nearest') {
      let best = null;
      for (const s of series) {
        if (s.unlisted) continue;
        for (let i = 0; i < s.xs.length; i++) {
          const d = Math.hypot(frame.px(s.xs[i]) - hover.x, frame.py(s.ys[i]) - hover.y);
          if (Number.isFinite(d) && (!best || d < best.d)) best = { d, s, i };
        }
      }
      if (!best) return;
      const { s, i } = best;
      const px = frame.px(s.xs[i]);
      const py = frame.py(s.ys[i]);
      context.save();
      context.strokeStyle = s.colour;
      context.lineWidth = 1.5;
      context.beginPath();
      context.arc(px, py, 5, 0, TAU);
      context.stroke();
      context.restore();
      lines = plot.spec.describe(s, i);
    } else {
      const x = frame.fromPx(hover.x);
      drawLine(context, [hover.x, frame.top], [hover.x, frame.bottom], '#9aa2b1', 1, [3, 3]);
      lines = [`${plot.spec.xLabel} = ${fmt(x, 5)}`];
      for (const s of series) {
        if (s.unlisted) continue;
        const y = s.valueAtX ? s.valueAtX(x) : null;
        lines.push(`${s.label} = ${fmt(y, 6)}`);
        if (Number.isFinite(y)) {
          context.fillStyle = s.colour;
          context.beginPath();
          context.arc(hover.x, frame.py(y), 3, 0, TAU);
          context.fill();
        }
      }
    }
    tooltip.element.textContent = lines.join('\n');
    tooltip.element.hidden = false;
    tooltip.element.style.left = `${hover.clientX + 14}px`;
    tooltip.element.style.top = `${hover.clientY + 14}px`;
  }

  // ---------------------------------------------------------------------------------------
  // The plots of a run: coordinates against t, phase portraits, drifts, constraint forces.

  const options = { unwrap: false };

  /** A coordinate's values as plotted: angles wrapped unless the user unwraps them. */
  function shown(coordinate, values) {
    return coordinate.angle && !options.unwrap ? values.map((v) => (Number.isFinite(v) ? wrap(v) : v)) : values;
  }

  /** Breaks a wrapped angle's curve at each wrap instead of drawing a vertical line. */
  function wrapBreaks(coordinate) {
    return coordinate.angle && !options.unwrap ? (x0, y0, x1, y1) => Math.abs(y1 - y0) > Math.PI : null;
  }

  /** A series against t, with its value at any t for the hover readout. */
  function timeSeries(label, colour, values, transform) {
    const ys = transform ? transform(values) : values;
    return {
      label, colour, xs: data.time, ys,
      valueAtX: (t) => valueAt(ys, locate(t)),
    };
  }

  function setUpPlots() {
    const coordinateHolder = document.getElementById('coordinate-plots');
    if (!data.coordinates.length || data.time.length === 0) {
      coordinateHolder.append(note('The run has no coordinates to plot.'));
    }
    const timeRange = [0, Math.max(data.until, data.time.length ? data.time[data.time.length - 1] : 0) || 1];
    data.coordinates.forEach((c, k) => {
      if (!data.time.length) return;
      const colour = PALETTE[k % PALETTE.length];
      makePlot(coordinateHolder, {
        title: () => `${c.name} against t${c.angle ? (options.unwrap ? ' (an angle, unwrapped)' : ' (an angle, wrapped to (−π, π])') : ''}`,
        xLabel: 't', yLabel: c.name, hover: 'time', xRange: timeRange, unwraps: c.angle,
        series: () => {
          const s = timeSeries(c.name, colour, c.q, (v) => shown(c, v));
          s.breaks = wrapBreaks(c);
          return [s];
        },
        marker: (at) => {
          const q = valueAt(c.q, at);
          return { lines: [clock.t], dots: [{ x: clock.t, y: c.angle && !options.unwrap && q !== null ? wrap(q) : q, colour }] };
        },
      });
      makePlot(coordinateHolder, {
        title: `phase portrait: ${c.name}′ against ${c.name}`,
        xLabel: c.name, yLabel: `${c.name}′`, hover: 'nearest', unwraps: c.angle,
        series: () => {
          const xs = shown(c, c.q);
          const breaks = wrapBreaks(c);
          return [{ label: `${c.name}′`, colour, xs, ys: c.qd, breaks: breaks ? (x0, y0, x1) => Math.abs(x1 - x0) > Math.PI : null }];
        },
        describe: (s, i) => [`t = ${fmt(data.time[i], 5)}`, `${c.name} = ${fmt(s.xs[i], 6)}`, `${c.name}′ = ${fmt(s.ys[i], 6)}`],
        marker: (at) => {
          const q = valueAt(c.q, at);
          return { dots: [{ x: c.angle && !options.unwrap && q !== null ? wrap(q) : q, y: valueAt(c.qd, at), colour }] };
        },
      });
    });

    const hasAngle = data.coordinates.some((c) => c.angle);
    const unwrap = document.getElementById('unwrap');
    unwrap.parentElement.hidden = !hasAngle;
    unwrap.addEventListener('change', () => {
      options.unwrap = unwrap.checked;
      for (const plot of plots) if (plot.spec.unwraps) layoutPlot(plot);
    });

    setUpDriftPlots(timeRange);
    setUpForcePlots(timeRange);
  }

  /** The drift (value − initial) of each quantity the derivation says is conserved. */
  function setUpDriftPlots(timeRange) {
    const holder = document.getElementById('drift-plots');
    const conserved = data.invariants.filter((v) => v.conserved && v.values.length);
    const notConserved = data.invariants.filter((v) => !v.conserved).map((v) => v.name);
    if (!conserved.length) holder.append(note('The derivation names no conserved quantity for this run.'));
    conserved.forEach((v, k) => {
      const initial = v.values[0];
      const colour = PALETTE[(k + 3) % PALETTE.length];
      makePlot(holder, {
        title: `${v.name} − ${v.name}(0): drift of a conserved quantity`,
        xLabel: 't', yLabel: `${v.name} − ${v.name}(0)`, hover: 'time', xRange: timeRange,
        series: () => [timeSeries(`${v.name} − ${v.name}(0)`, colour, v.values, (vs) => vs.map((x) => x - initial))],
        marker: (at) => ({ lines: [clock.t], dots: [{ x: clock.t, y: valueAt(v.values, at) - initial, colour }] }),
      });
    });
    if (notConserved.length) {
      holder.parentElement.insertBefore(
        note(`Not plotted, as the derivation says they are not conserved: ${notConserved.join(', ')}.`),
        holder.nextSibling,
      );
    }
  }

  function setUpForcePlots(timeRange) {
    const holder = document.getElementById('force-plots');
    if (!data.constraintForces.length || !data.time.length) {
      holder.hidden = true;
      document.getElementById('force-title').hidden = true;
      return;
    }
    data.constraintForces.forEach((f, k) => {
      const colour = PALETTE[(k + 1) % PALETTE.length];
      makePlot(holder, {
        title: `constraint force of ${f.name}`,
        xLabel: 't', yLabel: f.name, hover: 'time', xRange: timeRange,
        series: () => [timeSeries(f.name, colour, f.values)],
        marker: (at) => ({ lines: [clock.t], dots: [{ x: clock.t, y: valueAt(f.values, at), colour }] }),
      });
    });
  }

  function note(text) {
    const p = document.createElement('p');
    p.className = 'note';
    p.textContent = text;
    return p;
  }

  // ---------------------------------------------------------------------------------------
  // The audit: the invariants' drift, the constraints, and how the run was made.

  function table(headings, rows) {
    const element = document.createElement('table');
    const head = element.createTHead().insertRow();
    for (const h of headings) {
      const th = document.createElement('th');
      th.textContent = h;
      head.append(th);
    }
    const body = element.createTBody();
    for (const row of rows) {
      const tr = body.insertRow();
      row.forEach((cell, k) => {
        const td = tr.insertCell();
        if (cell && typeof cell === 'object') {
          td.textContent = cell.text;
          td.className = cell.className;
        } else {
          td.textContent = cell;
          if (k > 0) td.className = 'number';
        }
      });
    }
    return element;
  }

  /** A cell for a number or any other JSON value. */
  function cell(value, digits) {
    if (typeof value === 'number') return fmt(value, digits);
    if (value === null || value === undefined) return '—';
    return typeof value === 'object' ? JSON.stringify(value) : String(value);
  }

  function setUpAudit() {
    const holder = document.getElementById('audit-tables');
    const summary = data.summary;
    const invariants = summary.invariants && typeof summary.invariants === 'object' ? Object.entries(summary.invariants) : [];
    if (invariants.length) {
      holder.append(table(
        ['quantity', 'initial', 'final', 'max abs drift', 'max rel drift', 'conserved'],
        invariants.map(([name, v]) => [
          name, cell(v.initial, 10), cell(v.final, 10), cell(v.max_abs_drift, 3), cell(v.max_rel_drift, 3),
          v.conserved
            ? { text: '✓ conserved', className: 'conserved' }
            : { text: 'not conserved', className: 'not-conserved' },
        ]),
      ));
    } else {
      holder.append(note('The run audited no invariants.'));
    }
    const constraints = summary.constraints && typeof summary.constraints === 'object' ? Object.entries(summary.constraints) : [];
    if (constraints.length) {
      const keys = [...new Set(constraints.flatMap(([, c]) => Object.keys(c || {})))];
      holder.append(table(
        ['constraint', ...keys.map((k) => k.replace(/_/g, ' '))],
        constraints.map(([name, c]) => [name, ...keys.map((k) => cell((c || {})[k], 4))]),
      ));
    }
    const run = document.createElement('dl');
    run.className = 'run';
    const facts = [
      ['method', summary.method], ['steps', summary.steps], ['rejected steps', summary.rejected_steps],
      ['right-hand side evaluations', summary.rhs_evaluations], ['rtol', summary.rtol], ['atol', summary.atol],
      ['fixed step dt', summary.dt], ['tolerance controls', summary.tolerance_controls], ['final time', summary.t_final],
      ['stopped by', summary.stopped_by], ['failure', summary.failure_reason || summary.failure],
    ];
    for (const [name, value] of facts) {
      if (value === undefined || value === null || value === '') continue;
      const dt = document.createElement('dt');
      dt.textContent = name;
      const dd = document.createElement('dd');
      dd.textContent = cell(value, 6);
      run.append(dt, dd);
    }
    for (const warning of Array.isArray(summary.warnings) ? summary.warnings : []) {
      const dt = document.createElement('dt');
      dt.textContent = 'warning';
      const dd = document.createElement('dd');
      dd.textContent = cell(warning);
      run.append(dt, dd);
    }
    if (run.children.length) holder.append(run);
  }

  // ---------------------------------------------------------------------------------------
  // The analyses: normal modes, the orbit, the top. Each draws into small canvases that
  // follow the shown time.

  const analysisViews = []; // {canvas, layout(), draw()}

  function figure(parent, captionText) {
    const element = document.createElement('figure');
    element.className = 'analysis';
    const canvas = document.createElement('canvas');
    canvas.setAttribute('aria-label', captionText);
    const caption = document.createElement('figcaption');
    caption.textContent = captionText;
    element.append(canvas, caption);
    parent.append(element);
    return canvas;
  }

  function setUpAnalyses() {
    const holder = document.getElementById('analyses-content');
    const { modes, orbit, top, section } = data.analyses;
    let any = false;
    if (modes && Array.isArray(modes.frequencies) && modes.frequencies.length) any = setUpModes(holder, modes) || any;
    if (orbit && typeof orbit === 'object') any = setUpOrbit(holder, orbit) || any;
    if (top && typeof top === 'object') any = setUpTop(holder, top) || any;
    if (section && typeof section === 'object') any = setUpSection(holder, section) || any;
    document.getElementById('analyses').hidden = !any;
  }

  function heading(parent, text) {
    const h = document.createElement('h3');
    h.textContent = text;
    parent.append(h);
  }

  /**
   * A Poincaré section (`report --section`): its points in the plane; the point last
   * reached at the shown time is marked, and hovering a point tells when it was reached.
   */
  function setUpSection(holder, section) {
    const numbers = (value) => (Array.isArray(value) ? value.map((v) => (Number.isFinite(v) ? v : NaN)) : []);
    const [ts, xs, ys] = [numbers(section.t), numbers(section.x), numbers(section.y)];
    const axes = Array.isArray(section.axes) && section.axes.length === 2 ? section.axes.map(String) : ['x', 'y'];
    const total = Number.isInteger(section.points) ? section.points : xs.length;
    const way = section.falling ? 'decreasing' : 'increasing';
    heading(holder, `Poincaré section ${String(section.condition || '')} (${way})`);
    const grid = document.createElement('div');
    grid.className = 'analysis-grid';
    holder.append(grid);
    if (!xs.length || xs.length !== ys.length || xs.length !== ts.length) {
      const note = document.createElement('p');
      note.className = 'note';
      note.textContent = 'The run did not cross the section.';
      holder.append(note);
      return true;
    }
    const shown = xs.length < total ? `, every ${Math.ceil(total / xs.length)}th shown` : '';
    makePlot(grid, {
      title: `${total} points in the plane (${axes[0]}, ${axes[1]})${shown}`,
      xLabel: axes[0],
      yLabel: axes[1],
      hover: 'nearest',
      series: () => [{ label: 'points', colour: PALETTE[0], xs, ys, dots: true }],
      describe: (s, i) => [`t = ${fmt(ts[i], 6)}`, `${axes[0]} = ${fmt(xs[i], 6)}`, `${axes[1]} = ${fmt(ys[i], 6)}`],
      marker: () => {
        let k = -1;
        while (k + 1 < ts.length && ts[k + 1] <= clock.t) k++;
        return { dots: k < 0 ? [] : [{ x: xs[k], y: ys[k], colour: PALETTE[1] }] };
      },
    });
    return true;
  }

  /** How a mode's shape reads: (q1, q2) ∝ (v1, v2). */
  function modeShape(modes, k) {
    const shape = Array.isArray(modes.modes) ? modes.modes[k] : null;
    const names = Array.isArray(modes.coordinates) ? modes.coordinates : [];
    if (!Array.isArray(shape) || shape.length !== names.length || !names.length) return '';
    return ` — (${names.join(', ')}) ∝ (${shape.map((v) => fmt(v, 3)).join(', ')})`;
  }

  /** Each normal mode animated from its frames; a mode of frequency 0 replays its drift. */
  function setUpModes(holder, modes) {
    const frames = Array.isArray(modes.points) ? modes.points : [];
    heading(holder, 'Normal modes');
    const grid = document.createElement('div');
    grid.className = 'analysis-grid';
    holder.append(grid);
    // Only the modes that come with frames are animated (the lowest ones of a
    // large model); the others are listed below the grid.
    const unanimated = modes.frequencies.slice(frames.length);
    if (unanimated.length) {
      const note = document.createElement('p');
      note.className = 'note';
      note.textContent = `Modes ${frames.length + 1} to ${modes.frequencies.length}, not animated: Ω = ${unanimated.map((w) => fmt(w)).join(', ')}.`;
      holder.append(note);
    }
    modes.frequencies.slice(0, frames.length).forEach((omega, k) => {
      const pointFrames = Array.isArray(frames[k]) ? frames[k] : [];
      const drift = !(Math.abs(omega) > 1e-9);
      const period = drift ? DRIFT_MODE_SECONDS : TAU / omega;
      const slowed = !drift && period < SHORTEST_MODE_PERIOD;
      const label = drift
        ? `mode ${k + 1}: Ω = 0, a drift, not an oscillation${modeShape(modes, k)}`
        : `mode ${k + 1}: Ω = ${fmt(omega)}, period ${fmt(period)}${slowed ? ' (shown slowed down)' : ''}${modeShape(modes, k)}`;
      const canvas = figure(grid, label);
      const count = Math.max(0, ...pointFrames.map((p) => (p && Array.isArray(p.x) ? p.x.length : 0)));
      const framePosition = (p, j) => {
        const frame = pointFrames[p];
        if (!frame || !Array.isArray(frame.x)) return null;
        return [frame.x[j], frame.y[j], Array.isArray(frame.z) ? frame.z[j] : 0];
      };
      const places = [];
      if ([...data.rods, ...data.springs].some(([a, b]) => a === -1 || b === -1) || data.dimension === 3) places.push([0, 0, 0]);
      pointFrames.forEach((_, p) => {
        for (let j = 0; j < count; j++) {
          const at = framePosition(p, j);
          if (at) places.push(at);
        }
      });
      const bounds = boundsOf(places);
      const view = { canvas, context: null, width: 0, height: 0 };
      view.layout = () => Object.assign(view, fitCanvas(canvas));
      view.draw = () => {
        const { context, width, height } = view;
        context.clearRect(0, 0, width, height);
        if (!count) return;
        const base = Math.min(11, Math.max(5, Math.min(width, height) / 28));
        const camera = viewFor(bounds, width, height, base + 16);
        if (data.dimension === 3) drawSpaceAxes(context, camera, bounds.radius * 0.5);
        // Each point's path in this mode, faint: shows along which line a mode moves.
        pointFrames.forEach((_, p) => {
          context.save();
          context.strokeStyle = PALETTE[p % PALETTE.length] + '55';
          context.lineWidth = 1.2;
          context.beginPath();
          for (let j = 0; j < count; j++) {
            const at = framePosition(p, j);
            if (!at || !at.every(Number.isFinite)) continue;
            const s = camera.project(at);
            if (j === 0) context.moveTo(s[0], s[1]);
            else context.lineTo(s[0], s[1]);
          }
          context.stroke();
          context.restore();
        });
        // Where in its cycle (or drift) the mode is at the shown time.
        const shownPeriod = drift ? DRIFT_MODE_SECONDS : Math.max(period, SHORTEST_MODE_PERIOD);
        const phase = (clock.t / shownPeriod) % 1;
        const position = phase * (drift ? count - 1 : count);
        const j0 = Math.floor(position);
        const j1 = drift ? Math.min(j0 + 1, count - 1) : (j0 + 1) % count;
        const f = position - j0;
        const positions = data.points.map((_, p) => {
          const a = framePosition(p, Math.min(j0, count - 1));
          const b = framePosition(p, j1);
          if (!a || !b) return null;
          return [0, 1, 2].map((c) => a[c] + f * (b[c] - a[c]));
        });
        drawMechanism(context, camera, positions, null, base, false);
      };
      makeTurnable(canvas);
      analysisViews.push(view);
    });
    return true;
  }

  /** The orbit: U_eff with the energy line and the turning radii, and the path with its turning circles. */
  function setUpOrbit(holder, orbit) {
    heading(holder, `Orbit${orbit.kind ? `: ${orbit.kind}` : ''}`);
    const grid = document.createElement('div');
    grid.className = 'analysis-grid';
    holder.append(grid);
    const turning = [orbit.periapsis, orbit.apoapsis].filter((r) => Number.isFinite(r) && r > 0);
    const energy = Number.isFinite(orbit.energy) ? orbit.energy : null;
    const ueff = orbit.u_eff && Array.isArray(orbit.u_eff.r) && Array.isArray(orbit.u_eff.u) ? orbit.u_eff : null;
    const moving = data.points[0] || null;
    const radiusAt = (at) => {
      if (!moving) return null;
      const p = pointAt(moving, at);
      return p.every(Number.isFinite) ? Math.hypot(p[0], p[1], p[2]) : null;
    };
    if (ueff) {
      const rRange = extent([ueff.r]) || [0, 1];
      const uMin = (extent([ueff.u]) || [0, 1])[0];
      const top = energy !== null ? Math.max(energy + Math.max(energy - uMin, 1e-9) * 1.5, uMin + 1e-9) : uMin + 1;
      makePlot(grid, {
        title: `U_eff(r) with the energy E = ${fmt(energy)} and the turning radii ${turning.map((r) => fmt(r)).join(', ')}`,
        xLabel: 'r', yLabel: 'U_eff', hover: 'nearest', xRange: rRange,
        yRange: [uMin - (top - uMin) * 0.08, top],
        series: () => {
          const series = [{ label: 'U_eff', colour: PALETTE[0], xs: ueff.r, ys: ueff.u, width: 1.8 }];
          if (energy !== null) series.push({ label: 'E', colour: PALETTE[1], xs: rRange, ys: [energy, energy], dash: [5, 4] });
          for (const r of turning) series.push({ label: '', unlisted: true, colour: '#9aa2b1', xs: [r, r], ys: [uMin - 1e9, 1e9], dash: [2, 3] });
          return series;
        },
        describe: (s, i) => [`r = ${fmt(s.xs[i], 5)}`, `${s.label} = ${fmt(s.ys[i], 5)}`],
        marker: (at) => ({ dots: [{ x: radiusAt(at), y: energy, colour: PALETTE[1] }] }),
      });
    }
    if (moving) {
      const canvas = figure(grid, `the path of ${moving.name} with the turning circles r = ${turning.map((r) => fmt(r)).join(', ') || '—'}`);
      const places = [[0, 0, 0]];
      for (let i = 0; i < moving.x.length; i++) places.push([moving.x[i], moving.y[i], moving.z ? moving.z[i] : 0]);
      for (const r of turning) places.push([r, r, 0], [-r, -r, 0]);
      const bounds = boundsOf(places);
      const view = { canvas };
      view.layout = () => Object.assign(view, fitCanvas(canvas));
      view.draw = () => drawOrbit(view, bounds, moving, turning);
      makeTurnable(canvas);
      analysisViews.push(view);
    }
    return Boolean(ueff || moving);
  }

  function drawOrbit(view, bounds, moving, turning) {
    const { context, width, height } = view;
    context.clearRect(0, 0, width, height);
    const camera = data.dimension === 3
      ? view3D([0, 0, 0], bounds.radius + Math.hypot(...bounds.centre), width, height, 14)
      : view2D(bounds.box, width, height, 14);
    const centre = camera.project([0, 0, 0]);
    // A turning sphere's outline is a circle in any orthographic view.
    for (const r of turning) {
      context.save();
      context.strokeStyle = '#8e44ad';
      context.setLineDash([5, 4]);
      context.beginPath();
      context.arc(centre[0], centre[1], r * camera.scale, 0, TAU);
      context.stroke();
      context.restore();
    }
    context.save();
    context.strokeStyle = PALETTE[0] + '99';
    context.lineWidth = 1.3;
    context.beginPath();
    let drawing = false;
    for (let i = 0; i < moving.x.length; i++) {
      const p = [moving.x[i], moving.y[i], moving.z ? moving.z[i] : 0];
      if (!p.every(Number.isFinite)) {
        drawing = false;
        continue;
      }
      const s = camera.project(p);
      if (drawing) context.lineTo(s[0], s[1]);
      else context.moveTo(s[0], s[1]);
      drawing = true;
    }
    context.stroke();
    context.restore();
    drawLine(context, [centre[0] - 5, centre[1]], [centre[0] + 5, centre[1]], '#3b4252', 1.2);
    drawLine(context, [centre[0], centre[1] - 5], [centre[0], centre[1] + 5], '#3b4252', 1.2);
    const at = locate(clock.t);
    const p = at ? pointAt(moving, at) : null;
    if (p && p.every(Number.isFinite)) {
      const s = camera.project(p);
      drawLine(context, centre, s, '#9aa2b1', 1, [2, 3]);
      drawDisc(context, s, 6, PALETTE[0], '');
    }
  }

  /** The top's figure axis on the unit sphere, between the circles of its β bounds. */
  function setUpTop(holder, top) {
    const axis = top.axis && Array.isArray(top.axis.x) ? top.axis : null;
    if (!axis) return false;
    heading(holder, 'Top');
    const grid = document.createElement('div');
    grid.className = 'analysis-grid';
    holder.append(grid);
    const bounds = [top.beta_min, top.beta_max].filter(Number.isFinite);
    const canvas = figure(grid, `the figure axis e3 on the unit sphere, between β = ${bounds.map((b) => fmt(b)).join(' and β = ') || '—'}`);
    canvas.parentElement.classList.add('wide');
    const view = { canvas };
    view.layout = () => Object.assign(view, fitCanvas(canvas));
    view.draw = () => drawTopSphere(view, axis, bounds);
    makeTurnable(canvas);
    analysisViews.push(view);
    return true;
  }

  /** A polyline on the sphere: the side facing the camera solid, the far side faint. */
  function drawOnSphere(context, camera, points, colour, width) {
    for (let i = 1; i < points.length; i++) {
      const a = points[i - 1];
      const b = points[i];
      if (!a.every(Number.isFinite) || !b.every(Number.isFinite)) continue;
      const pa = camera.project(a);
      const pb = camera.project(b);
      context.globalAlpha = pa[2] + pb[2] >= 0 ? 1 : 0.25;
      drawLine(context, pa, pb, colour, width);
    }
    context.globalAlpha = 1;
  }

  function drawTopSphere(view, axis, betas) {
    const { context, width, height } = view;
    context.clearRect(0, 0, width, height);
    const camera = data.dimension === 3 ? view3D([0, 0, 0], 1.15, width, height, 10) : view2D([-1.15, 1.15, -1.15, 1.15], width, height, 10);
    const centre = camera.project([0, 0, 0]);
    context.save();
    context.strokeStyle = '#9aa2b1';
    context.beginPath();
    context.arc(centre[0], centre[1], camera.scale, 0, TAU);
    context.stroke();
    context.restore();
    drawSpaceAxes(context, camera, 1.1);
    const circle = (beta) =>
      Array.from({ length: 97 }, (_, k) => [Math.sin(beta) * Math.cos((k / 96) * TAU), Math.sin(beta) * Math.sin((k / 96) * TAU), Math.cos(beta)]);
    drawOnSphere(context, camera, circle(Math.PI / 2), '#d8dce3', 1);
    for (const beta of betas) drawOnSphere(context, camera, circle(beta), '#8e44ad', 1.5);
    const trace = axis.x.map((x, i) => [x, axis.y[i], axis.z[i]]);
    const at = locate(clock.t);
    const upTo = at ? at.i + 1 : trace.length;
    drawOnSphere(context, camera, trace, AXIS_COLOURS[2] + '40', 1);
    drawOnSphere(context, camera, trace.slice(0, upTo), AXIS_COLOURS[2], 1.6);
    if (at) {
      const e = [valueAt(axis.x, at), valueAt(axis.y, at), valueAt(axis.z, at)];
      if (e.every(Number.isFinite)) {
        const tip = camera.project(e);
        drawLine(context, centre, tip, AXIS_COLOURS[2], 2.5);
        drawDisc(context, tip, 4.5, AXIS_COLOURS[2], '');
      }
    }
  }

  // ---------------------------------------------------------------------------------------
  // Drawing everything that follows the shown time.

  /**
   * Redraws the stage, the plots' markers and the analyses at the shown time. During
   * playback (`onlyVisible`) pictures scrolled out of sight wait until they are seen again.
   */
  function render(onlyVisible = false) {
    const wanted = (item) => !onlyVisible || item.visible !== false;
    if (stage.context && wanted(stage)) drawStage();
    for (const plot of plots) if (wanted(plot)) drawPlot(plot);
    for (const view of analysisViews) if (view.context && wanted(view)) view.draw();
    updateControls();
  }

  /** Keeps `item.visible` up to date for a canvas, and draws the canvas when it comes into sight. */
  const sightings = new Map();
  const observer = 'IntersectionObserver' in window
    ? new IntersectionObserver((entries) => {
      let seen = false;
      for (const entry of entries) {
        const item = sightings.get(entry.target);
        item.visible = entry.isIntersecting;
        seen = seen || item.visible;
      }
      if (seen) render(true);
    })
    : null;

  function watch(item, canvas) {
    if (!observer) return;
    sightings.set(canvas, item);
    observer.observe(canvas);
  }

  /** Fits every canvas to its box again and redraws (on load and when the window resizes). */
  function layout() {
    if (stage.canvas) layoutStage();
    for (const plot of plots) layoutPlot(plot);
    for (const view of analysisViews) view.layout();
    render();
  }

  /** Starts watching which canvases are in sight (after they have their places on the page). */
  function watchAll() {
    watch(stage, stage.canvas);
    for (const plot of plots) watch(plot, plot.canvas);
    for (const view of analysisViews) watch(view, view.canvas);
  }

  // ---------------------------------------------------------------------------------------
  // The test interface: what a browser test asks of the page.

  /** One entry per point: what is drawn at the shown time, in model coordinates. */
  function positions() {
    const at = locate(clock.t);
    return data.points.map((point) => ({
      name: point.name,
      x: valueAt(point.x, at),
      y: valueAt(point.y, at),
      z: data.dimension === 3 && point.z ? valueAt(point.z, at) : null,
    }));
  }

  function main() {
    document.title = data.name || document.title;
    document.getElementById('model-name').textContent = data.name || 'lagrange report';
    const derivation = document.getElementById('derivation-content');
    if (data.derivation) derivation.innerHTML = data.derivation;
    else derivation.append(note('This report carries no derivation.'));

    tooltip.element = document.getElementById('tooltip');
    stage.canvas = document.getElementById('mechanism');
    stage.bounds = mechanismBounds();
    makeTurnable(stage.canvas);
    if (!data.points.length) {
      stage.canvas.parentElement.classList.add('empty');
      const empty = document.getElementById('mechanism-note');
      empty.hidden = false;
      empty.textContent = 'This model has no particles or bodies to draw; its motion is in the plots below.';
    }
    setUpControls();
    setUpPlots();
    setUpAudit();
    setUpAnalyses();
    layout();
    watchAll();

    let resizing = null;
    window.addEventListener('resize', () => {
      clearTimeout(resizing);
      resizing = setTimeout(layout, 100);
    });

    window.lagrangeReport = { time: () => clock.t, seek, positions, play, pause };
    if (data.time.length > 1 && data.until > 0) play();
  }

  main();
})();
