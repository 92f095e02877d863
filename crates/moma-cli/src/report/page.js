// The mission report's player: one clock drives the top view, the arm's side view, the
// 3-D view, the plots' cursors, the "now" table and the events list. State for headless checks is
// written on <body>: data-frame (sample index), data-time (s), data-plots-drawn,
// data-plots (how many there are), data-errors (captured by the first script).
(function () {
  'use strict';
  const D = JSON.parse(document.getElementById('mission-data').textContent);
  const S = D.samples;
  const N = S.t.length;
  const T0 = N ? S.t[0] : 0;
  const T1 = N ? S.t[N - 1] : 0;
  const body = document.body;
  const C = {
    path: '#d62728', plan: '#1f6fb4', planOld: 'rgba(31,111,180,0.35)', obstacle: '#ff8c1a',
    robot: '#2a9d8f', start: '#2ca02c', goal: '#8e44ad', replan: '#8e44ad', target: '#e6007e',
    grid: '#e8ebf0', axis: '#444', text: '#333', arm: '#264b73', ee: '#ff7f0e',
  };
  const SERIES = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#e377c2', '#17becf'];
  const FONT = '12px system-ui, -apple-system, "Segoe UI", Roboto, Arial, sans-serif';

  // ---------- small helpers ----------
  function fmt(x, digits) {
    if (x === null || x === undefined || !isFinite(x)) return '—';
    if (x === 0) return '0';
    const a = Math.abs(x);
    if (a >= 1e5 || a < 1e-3) return x.toExponential(2);
    return Number(x.toPrecision(digits || 4)).toString();
  }
  function niceTicks(lo, hi, maxN) {
    const span = hi - lo;
    if (!(span > 0)) return [lo];
    const raw = span / Math.max(2, maxN);
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    let step = mag;
    for (const m of [1, 2, 2.5, 5, 10]) { step = m * mag; if (span / step <= maxN) break; }
    const out = [];
    for (let t = Math.ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step && out.length < 30; t += step) {
      out.push(Math.abs(t) < 1e-12 * step ? 0 : t);
    }
    return out;
  }
  function el(tag, attrs, text) {
    const e = document.createElement(tag);
    if (attrs) for (const k in attrs) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    return e;
  }
  // index of the last sample with t <= time (0 before the first)
  function frameAt(time) {
    let lo = 0, hi = N - 1;
    if (N === 0 || time <= S.t[0]) return 0;
    if (time >= S.t[hi]) return hi;
    while (hi - lo > 1) { const m = (lo + hi) >> 1; if (S.t[m] <= time) lo = m; else hi = m; }
    return lo;
  }
  function angleLerp(a, b, f) {
    let d = b - a;
    while (d > Math.PI) d -= 2 * Math.PI;
    while (d < -Math.PI) d += 2 * Math.PI;
    return a + f * d;
  }
  // the base pose at `time`, interpolated between samples
  function poseAt(time) {
    if (N === 0) return { x: D.start[0], y: D.start[1], th: D.start[2] };
    const i = frameAt(time);
    const j = Math.min(i + 1, N - 1);
    const dt = S.t[j] - S.t[i];
    const f = dt > 0 ? Math.min(1, Math.max(0, (time - S.t[i]) / dt)) : 0;
    return {
      x: S.x[i] + f * (S.x[j] - S.x[i]),
      y: S.y[i] + f * (S.y[j] - S.y[i]),
      th: angleLerp(S.th[i], S.th[j], f),
    };
  }
  // a canvas sized to its CSS box at the device's pixel ratio; returns the drawing size
  function fit(canvas, aspect) {
    const w = Math.max(200, canvas.clientWidth || canvas.parentNode.clientWidth || 400);
    const h = Math.round(w * aspect);
    const dpr = Math.min(2, window.devicePixelRatio || 1);
    canvas.style.height = h + 'px';
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(h * dpr);
    const g = canvas.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    return { w: w, h: h, dpr: dpr, g: g };
  }
  function layer(w, h, dpr) {
    const c = document.createElement('canvas');
    c.width = Math.round(w * dpr);
    c.height = Math.round(h * dpr);
    const g = c.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    return { c: c, g: g };
  }
  function legendItem(box, kind, colour, label) {
    const s = el('span');
    const i = el('i', { class: kind });
    if (kind === 'line' || kind === 'dash') i.style.borderTopColor = colour; else i.style.background = colour;
    if (kind === 'ring') { i.className = 'disk'; i.style.background = 'transparent'; i.style.border = '2px solid ' + colour; }
    s.appendChild(i);
    s.appendChild(document.createTextNode(label));
    box.appendChild(s);
    return s;
  }

  // ---------- top view ----------
  const top = { canvas: document.getElementById('top') };
  const mapImg = new Image();
  let mapReady = false;
  if (D.map.png) {
    mapImg.onload = function () { mapReady = true; buildTopStatic(); draw(); };
    mapImg.src = D.map.png;
  }
  const M = { l: 52, r: 12, t: 10, b: 38 };
  function buildTopStatic() {
    const v = D.view;
    // the canvas takes the view's shape (within reason), so the map fills it
    const cw = Math.max(300, top.canvas.clientWidth || 700);
    const aspect = Math.min(1.1, Math.max(0.45, (v[3] - v[1]) / (v[2] - v[0])));
    const f = fit(top.canvas, aspect * (cw - M.l - M.r) / cw + (M.t + M.b) / cw);
    const aw = f.w - M.l - M.r, ah = f.h - M.t - M.b;
    const s = Math.min(aw / (v[2] - v[0]), ah / (v[3] - v[1]));
    const ox = M.l + 0.5 * (aw - s * (v[2] - v[0])), oy = M.t + 0.5 * (ah - s * (v[3] - v[1]));
    top.f = f;
    top.px = (x) => ox + (x - v[0]) * s;
    top.py = (y) => oy + (v[3] - y) * s;
    top.s = s;
    top.box = [ox, oy, s * (v[2] - v[0]), s * (v[3] - v[1])];
    const L = layer(f.w, f.h, f.dpr);
    const g = L.g;
    g.fillStyle = '#fff';
    g.fillRect(0, 0, f.w, f.h);
    g.save();
    g.beginPath();
    g.rect(top.box[0], top.box[1], top.box[2], top.box[3]);
    g.clip();
    g.fillStyle = '#c8c8c8';
    g.fillRect(top.box[0], top.box[1], top.box[2], top.box[3]);
    if (mapReady) {
      g.imageSmoothingEnabled = false;
      g.drawImage(mapImg, top.px(D.map.x0), top.py(D.map.y1), (D.map.x1 - D.map.x0) * s, (D.map.y1 - D.map.y0) * s);
    }
    g.restore();
    g.strokeStyle = C.axis;
    g.lineWidth = 1;
    g.strokeRect(top.box[0] + 0.5, top.box[1] + 0.5, top.box[2], top.box[3]);
    g.font = FONT;
    g.fillStyle = C.text;
    g.textAlign = 'center';
    g.textBaseline = 'top';
    const bottom = top.box[1] + top.box[3];
    for (const t of niceTicks(v[0], v[2], Math.max(3, Math.floor(top.box[2] / 70)))) {
      const x = top.px(t);
      g.beginPath(); g.moveTo(x, bottom); g.lineTo(x, bottom + 5); g.stroke();
      g.fillText(fmt(t), x, bottom + 7);
    }
    g.fillText('x [m]', top.box[0] + top.box[2] / 2, bottom + 22);
    g.textAlign = 'right';
    g.textBaseline = 'middle';
    for (const t of niceTicks(v[1], v[3], Math.max(3, Math.floor(top.box[3] / 60)))) {
      const y = top.py(t);
      g.beginPath(); g.moveTo(top.box[0], y); g.lineTo(top.box[0] - 5, y); g.stroke();
      g.fillText(fmt(t), top.box[0] - 7, y);
    }
    g.save();
    g.translate(12, top.box[1] + top.box[3] / 2);
    g.rotate(-Math.PI / 2);
    g.textAlign = 'center';
    g.fillText('y [m]', 0, 0);
    g.restore();
    // scale bar, lower left inside the map
    const span = (v[2] - v[0]) / 5;
    const mag = Math.pow(10, Math.floor(Math.log10(span)));
    const len = [5, 2, 1].map((m) => m * mag).find((l) => l <= span) || mag;
    const bx = top.box[0] + 10, by = bottom - 12;
    g.fillStyle = 'rgba(255,255,255,0.85)';
    g.fillRect(bx - 5, by - 20, len * s + 10, 26);
    g.strokeStyle = '#000'; g.lineWidth = 3;
    g.beginPath(); g.moveTo(bx, by); g.lineTo(bx + len * s, by); g.stroke();
    g.fillStyle = '#000'; g.textAlign = 'center'; g.textBaseline = 'bottom';
    g.fillText(fmt(len) + ' m', bx + len * s / 2, by - 4);
    top.layer = L.c;
  }
  function disk(g, x, y, r) { g.beginPath(); g.arc(x, y, r, 0, 2 * Math.PI); }
  function poseMarker(g, p, colour, fill) {
    const x = top.px(p[0]), y = top.py(p[1]);
    const r = Math.max(4, D.footprint_radius * top.s);
    disk(g, x, y, r);
    if (fill) { g.fillStyle = fill; g.fill(); }
    g.strokeStyle = colour; g.lineWidth = 2; g.stroke();
    arrow(g, x, y, x + r * Math.cos(p[2]), y - r * Math.sin(p[2]), colour);
  }
  function arrow(g, x0, y0, x1, y1, colour) {
    const a = Math.atan2(y1 - y0, x1 - x0), h = 7;
    g.strokeStyle = colour; g.fillStyle = colour; g.lineWidth = 2;
    g.beginPath(); g.moveTo(x0, y0); g.lineTo(x1, y1); g.stroke();
    g.beginPath(); g.moveTo(x1, y1);
    g.lineTo(x1 - h * Math.cos(a - 0.45), y1 - h * Math.sin(a - 0.45));
    g.lineTo(x1 - h * Math.cos(a + 0.45), y1 - h * Math.sin(a + 0.45));
    g.closePath(); g.fill();
  }
  function activePlan(time) {
    let k = -1;
    for (let i = 0; i < D.plans.length; i++) if (D.plans[i].t <= time + 1e-9) k = i;
    return k;
  }
  function drawTop(time, frame) {
    if (!top.layer) buildTopStatic();
    const g = top.f.g;
    g.clearRect(0, 0, top.f.w, top.f.h);
    g.drawImage(top.layer, 0, 0, top.f.w, top.f.h);
    g.save();
    g.beginPath();
    g.rect(top.box[0], top.box[1], top.box[2], top.box[3]);
    g.clip();
    g.lineJoin = 'round'; g.lineCap = 'round';
    const k = activePlan(time);
    D.plans.forEach(function (p, i) {
      if (i > k) return;
      const pts = p.p;
      if (pts.length < 4) return;
      g.beginPath();
      g.moveTo(top.px(pts[0]), top.py(pts[1]));
      for (let j = 2; j < pts.length; j += 2) g.lineTo(top.px(pts[j]), top.py(pts[j + 1]));
      if (i === k) { g.setLineDash([]); g.strokeStyle = C.plan; g.lineWidth = 3; }
      else { g.setLineDash([6, 5]); g.strokeStyle = C.planOld; g.lineWidth = 2; }
      g.stroke();
    });
    g.setLineDash([]);
    for (const o of D.obstacles) {
      if (o.t > time) continue;
      const x = top.px(o.c[0]), y = top.py(o.c[1]), r = Math.max(2, o.r * top.s);
      disk(g, x, y, r);
      g.fillStyle = 'rgba(255,140,26,0.75)'; g.fill();
      g.strokeStyle = '#b35300'; g.lineWidth = 1.5; g.stroke();
      const age = time - o.t;
      if (age < 1.5) { // a ring that widens and fades: "this just appeared"
        disk(g, x, y, r + 6 + 30 * age);
        g.strokeStyle = 'rgba(255,140,26,' + (1 - age / 1.5).toFixed(3) + ')';
        g.lineWidth = 3; g.stroke();
      }
    }
    // executed path so far
    if (N > 1 && frame > 0) {
      g.beginPath();
      g.moveTo(top.px(S.x[0]), top.py(S.y[0]));
      for (let i = 1; i <= frame; i++) g.lineTo(top.px(S.x[i]), top.py(S.y[i]));
      const p = poseAt(time);
      g.lineTo(top.px(p.x), top.py(p.y));
      g.strokeStyle = C.path; g.lineWidth = 2.2; g.stroke();
    }
    // re-plan markers where the robot was when each new plan was made
    D.plans.forEach(function (p, i) {
      if (i === 0 || p.t > time) return;
      const q = poseAt(p.t);
      const x = top.px(q.x), y = top.py(q.y);
      g.beginPath(); g.moveTo(x, y - 7); g.lineTo(x + 7, y); g.lineTo(x, y + 7); g.lineTo(x - 7, y); g.closePath();
      g.fillStyle = C.replan; g.fill(); g.strokeStyle = '#fff'; g.lineWidth = 1.2; g.stroke();
      g.font = 'bold ' + FONT; g.fillStyle = C.replan; g.textAlign = 'left'; g.textBaseline = 'bottom';
      g.fillText('re-plan ' + i, x + 9, y - 4);
    });
    poseMarker(g, D.start, C.start, null);
    poseMarker(g, D.goal, C.goal, null);
    if (D.ee_target) {
      const x = top.px(D.ee_target[0]), y = top.py(D.ee_target[1]);
      g.strokeStyle = C.target; g.lineWidth = 2;
      g.beginPath(); g.moveTo(x - 6, y - 6); g.lineTo(x + 6, y + 6); g.moveTo(x - 6, y + 6); g.lineTo(x + 6, y - 6); g.stroke();
    }
    const p = poseAt(time);
    poseMarker(g, [p.x, p.y, p.th], C.robot, 'rgba(42,157,143,0.35)');
    // the obstacles' labels last, on a white halo, so the robot never hides them; a label
    // the robot's footprint would cover goes below its obstacle instead
    g.font = FONT; g.textAlign = 'center'; g.lineJoin = 'round';
    const rx = top.px(p.x), ry = top.py(p.y), rr = D.footprint_radius * top.s + 4;
    for (const o of D.obstacles) {
      if (o.t > time) continue;
      const x = top.px(o.c[0]), y = top.py(o.c[1]), r = Math.max(2, o.r * top.s);
      const above = y - r - 3;
      const covered = Math.abs(x - rx) < rr + 30 && above - 14 < ry + rr && above > ry - rr;
      const ty = covered ? y + r + 3 : above;
      g.textBaseline = covered ? 'top' : 'bottom';
      const text = 't = ' + fmt(o.t) + ' s';
      g.strokeStyle = 'rgba(255,255,255,0.9)'; g.lineWidth = 4; g.strokeText(text, x, ty);
      g.fillStyle = '#8a4000'; g.fillText(text, x, ty);
    }
    g.restore();
  }
  function topLegend() {
    const box = document.getElementById('top-legend');
    legendItem(box, 'disk', '#fff', 'free').firstChild.style.border = '1px solid #999';
    legendItem(box, 'disk', '#2b2b2b', 'occupied');
    legendItem(box, 'disk', '#c8c8c8', 'unknown');
    legendItem(box, 'line', C.plan, 'active plan');
    legendItem(box, 'dash', C.planOld, 'earlier plans');
    legendItem(box, 'line', C.path, 'executed path');
    legendItem(box, 'disk', C.obstacle, 'obstacle (from its time on)');
    legendItem(box, 'disk', C.replan, 're-plan point');
    legendItem(box, 'disk', 'rgba(42,157,143,0.6)', 'robot footprint, heading');
    legendItem(box, 'ring', C.start, 'start');
    legendItem(box, 'ring', C.goal, 'goal');
    if (D.ee_target) legendItem(box, 'disk', C.target, 'end-effector target (x, y)');
  }

  // ---------- side view of the arm ----------
  const side = { canvas: document.getElementById('side') };
  function buildSideStatic() {
    const f = fit(side.canvas, 0.72);
    const R = D.footprint_radius;
    let x0 = -R, x1 = R, z0 = 0, z1 = 0;
    for (const a of S.arm) for (let j = 0; j < a.length; j += 2) {
      if (a[j] === null || a[j + 1] === null) continue;
      x0 = Math.min(x0, a[j]); x1 = Math.max(x1, a[j]); z0 = Math.min(z0, a[j + 1]); z1 = Math.max(z1, a[j + 1]);
    }
    const pad = 0.08 * Math.max(x1 - x0, z1 - z0, 0.2);
    x0 -= pad; x1 += pad; z0 -= pad; z1 += pad;
    const m = { l: 46, r: 10, t: 10, b: 36 };
    const aw = f.w - m.l - m.r, ah = f.h - m.t - m.b;
    const s = Math.min(aw / (x1 - x0), ah / (z1 - z0));
    const ox = m.l + 0.5 * (aw - s * (x1 - x0)), oy = m.t + 0.5 * (ah - s * (z1 - z0));
    side.f = f;
    side.px = (x) => ox + (x - x0) * s;
    side.pz = (z) => oy + (z1 - z) * s;
    side.box = [ox, oy, s * (x1 - x0), s * (z1 - z0)];
    side.range = [x0, z0, x1, z1];
    const L = layer(f.w, f.h, f.dpr);
    const g = L.g;
    g.fillStyle = '#fff'; g.fillRect(0, 0, f.w, f.h);
    g.font = FONT; g.strokeStyle = C.grid; g.lineWidth = 1;
    const xt = niceTicks(x0, x1, Math.max(3, Math.floor(side.box[2] / 60)));
    const zt = niceTicks(z0, z1, Math.max(3, Math.floor(side.box[3] / 50)));
    for (const t of xt) { g.beginPath(); g.moveTo(side.px(t), side.box[1]); g.lineTo(side.px(t), side.box[1] + side.box[3]); g.stroke(); }
    for (const t of zt) { g.beginPath(); g.moveTo(side.box[0], side.pz(t)); g.lineTo(side.box[0] + side.box[2], side.pz(t)); g.stroke(); }
    g.strokeStyle = C.axis; g.strokeRect(side.box[0] + 0.5, side.box[1] + 0.5, side.box[2], side.box[3]);
    g.fillStyle = C.text; g.textAlign = 'center'; g.textBaseline = 'top';
    const bottom = side.box[1] + side.box[3];
    for (const t of xt) g.fillText(fmt(t), side.px(t), bottom + 5);
    g.fillText('forward x [m]', side.box[0] + side.box[2] / 2, bottom + 20);
    g.textAlign = 'right'; g.textBaseline = 'middle';
    for (const t of zt) g.fillText(fmt(t), side.box[0] - 6, side.pz(t));
    g.save(); g.translate(11, side.box[1] + side.box[3] / 2); g.rotate(-Math.PI / 2);
    g.textAlign = 'center'; g.fillText('up z [m]', 0, 0); g.restore();
    // the base frame's x axis and the footprint's extent along it
    g.strokeStyle = '#8a94a6'; g.setLineDash([4, 4]); g.lineWidth = 1;
    g.beginPath(); g.moveTo(side.box[0], side.pz(0)); g.lineTo(side.box[0] + side.box[2], side.pz(0)); g.stroke();
    g.setLineDash([]);
    // the base: the footprint's extent along x, from the ground (z = 0) up to the arm's
    // mount (the lowest first joint of the run), so the arm stands on it
    let mount = null;
    for (const a of S.arm) if (a && a.length >= 2 && a[1] !== null) mount = mount === null ? a[1] : Math.min(mount, a[1]);
    const mountZ = mount === null ? 0 : Math.max(mount, 0);
    g.fillStyle = 'rgba(42,157,143,0.35)'; g.strokeStyle = C.robot; g.lineWidth = 1.5;
    const bh = Math.max(side.pz(0) - side.pz(mountZ), 8);
    g.fillRect(side.px(-R), side.pz(0) - bh, side.px(R) - side.px(-R), bh);
    g.strokeRect(side.px(-R), side.pz(0) - bh, side.px(R) - side.px(-R), bh);
    // the ground
    g.strokeStyle = '#555'; g.lineWidth = 2;
    g.beginPath(); g.moveTo(side.box[0], side.pz(0)); g.lineTo(side.box[0] + side.box[2], side.pz(0)); g.stroke();
    g.fillStyle = C.text; g.textAlign = 'left'; g.textBaseline = 'bottom';
    g.fillText('base', side.px(-R) + 4, side.pz(0) - 3);
    side.layer = L.c;
  }
  function drawSide(time, frame) {
    if (!side.layer) buildSideStatic();
    const g = side.f.g;
    g.clearRect(0, 0, side.f.w, side.f.h);
    g.drawImage(side.layer, 0, 0, side.f.w, side.f.h);
    const a = N ? S.arm[frame] : null;
    if (!a || a.length < 2) {
      g.fillStyle = C.text; g.font = FONT; g.textAlign = 'center';
      g.fillText('no arm data', side.f.w / 2, side.f.h / 2);
      return;
    }
    // end-effector trace so far
    g.beginPath();
    let started = false;
    for (let i = 0; i <= frame; i++) {
      const b = S.arm[i];
      if (!b || b.length < 2) continue;
      const x = side.px(b[b.length - 2]), z = side.pz(b[b.length - 1]);
      if (!started) { g.moveTo(x, z); started = true; } else g.lineTo(x, z);
    }
    g.strokeStyle = 'rgba(255,127,14,0.45)'; g.lineWidth = 1.5; g.stroke();
    if (D.ee_target) { // the target in the base frame's x–z plane (its lateral offset named)
      const p = poseAt(time);
      const dx = D.ee_target[0] - p.x, dy = D.ee_target[1] - p.y;
      const fwd = dx * Math.cos(p.th) + dy * Math.sin(p.th);
      const lat = -dx * Math.sin(p.th) + dy * Math.cos(p.th);
      const r = side.range;
      if (fwd >= r[0] && fwd <= r[2] && D.ee_target[2] >= r[1] && D.ee_target[2] <= r[3]) {
        const x = side.px(fwd), z = side.pz(D.ee_target[2]);
        g.strokeStyle = C.target; g.lineWidth = 2;
        g.beginPath(); g.moveTo(x - 6, z - 6); g.lineTo(x + 6, z + 6); g.moveTo(x - 6, z + 6); g.lineTo(x + 6, z - 6); g.stroke();
        g.fillStyle = C.target; g.font = FONT; g.textAlign = 'left'; g.textBaseline = 'bottom';
        g.fillText('target (lateral ' + fmt(lat, 2) + ' m)', x + 8, z - 4);
      }
    }
    g.lineCap = 'round'; g.lineJoin = 'round';
    g.beginPath();
    g.moveTo(side.px(a[0]), side.pz(a[1]));
    for (let j = 2; j < a.length; j += 2) g.lineTo(side.px(a[j]), side.pz(a[j + 1]));
    g.strokeStyle = C.arm; g.lineWidth = 5; g.stroke();
    for (let j = 0; j + 2 < a.length; j += 2) {
      disk(g, side.px(a[j]), side.pz(a[j + 1]), 4);
      g.fillStyle = '#fff'; g.fill(); g.strokeStyle = C.arm; g.lineWidth = 2; g.stroke();
    }
    disk(g, side.px(a[a.length - 2]), side.pz(a[a.length - 1]), 6);
    g.fillStyle = C.ee; g.fill(); g.strokeStyle = '#7a3b00'; g.lineWidth = 1.2; g.stroke();
  }
  function sideLegend() {
    const box = document.getElementById('side-legend');
    legendItem(box, 'line', C.arm, 'links');
    legendItem(box, 'ring', C.arm, 'joint origins');
    legendItem(box, 'disk', C.ee, 'end effector');
    legendItem(box, 'line', 'rgba(255,127,14,0.6)', 'its trace');
    legendItem(box, 'disk', 'rgba(42,157,143,0.6)', 'base (footprint extent, ground to arm mount)');
    if (D.ee_target) legendItem(box, 'disk', C.target, 'target (projected)');
  }

  // ---------- plots ----------
  const PLOTS = [
    { title: 'Forward speed', unit: 'm/s', series: [{ k: 'v', n: 'executed v' }, { k: 'vr', n: 'reference', dash: true }] },
    { title: 'Turn rate', unit: 'rad/s', series: [{ k: 'w', n: 'executed ω' }, { k: 'wr', n: 'reference', dash: true }] },
    { title: 'ZMP margin (tip-over at 0; gaps: undefined)', unit: 'm', zero: true, series: [{ k: 'zmp', n: 'ZMP margin' }] },
    { title: 'Force-Angle minimum (tip-over at 0)', unit: 'rad', zero: true, series: [{ k: 'fa', n: 'FA minimum' }] },
    { title: 'Tracking error (distance from the reference)', unit: 'm', series: [{ k: 'err', n: 'tracking error' }] },
    { title: 'Clearance (footprint edge to the nearest obstacle)', unit: 'm', zero: true, series: [{ k: 'clr', n: 'clearance' }] },
  ];
  if (D.torque_names.length) {
    PLOTS.push({ title: 'Joint torques', unit: 'N·m', series: D.torque_names.map((n, i) => ({ col: S.tq[i], n: n })) });
  }
  const PM = { l: 54, r: 10, t: 8, b: 30 };
  let plotsDrawn = 0;
  function setupPlots() {
    const host = document.getElementById('plots');
    PLOTS.forEach(function (P) {
      const panel = el('div', { class: 'panel plot-panel' });
      const head = el('div', { class: 'plot-head' });
      head.appendChild(el('h3', null, P.title));
      head.appendChild(el('span', { class: 'unit' }, '[' + P.unit + ']'));
      panel.appendChild(head);
      P.canvas = el('canvas', { class: 'plot', 'aria-label': P.title });
      panel.appendChild(P.canvas);
      P.legend = el('div', { class: 'legend' });
      panel.appendChild(P.legend);
      P.series.forEach(function (s, i) {
        s.col = s.col || S[s.k];
        s.colour = SERIES[i % SERIES.length];
        const item = legendItem(P.legend, s.dash ? 'dash' : 'line', s.colour, s.n + ' ');
        s.value = el('b', null, '—');
        item.appendChild(s.value);
      });
      host.appendChild(panel);
      function seekFrom(ev) {
        const r = P.canvas.getBoundingClientRect();
        const x = ev.clientX - r.left;
        seek(P.t0 + (x - PM.l) / (P.w - PM.l - PM.r) * (P.t1 - P.t0));
      }
      P.canvas.addEventListener('mousedown', function (ev) { seekFrom(ev); P.drag = true; });
      P.canvas.addEventListener('mousemove', function (ev) { if (P.drag && ev.buttons & 1) seekFrom(ev); });
      window.addEventListener('mouseup', function () { P.drag = false; });
    });
    body.dataset.plots = String(PLOTS.length);
  }
  function buildPlotStatic(P) {
    const f = fit(P.canvas, 0.42);
    P.f = f; P.w = f.w; P.h = f.h;
    let lo = Infinity, hi = -Infinity;
    for (const s of P.series) for (const v of s.col) if (v !== null && isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (P.zero) { lo = Math.min(lo, 0); hi = Math.max(hi, 0); }
    if (!isFinite(lo)) { lo = -1; hi = 1; }
    if (hi - lo < 1e-9 * (1 + Math.abs(lo))) { lo -= 0.5 * (1e-3 + Math.abs(lo) * 1e-3); hi += 0.5 * (1e-3 + Math.abs(hi) * 1e-3); }
    const pad = 0.06 * (hi - lo);
    lo -= pad; hi += pad;
    P.t0 = T0; P.t1 = T1 > T0 ? T1 : T0 + 1;
    const aw = f.w - PM.l - PM.r, ah = f.h - PM.t - PM.b;
    P.px = (t) => PM.l + (t - P.t0) / (P.t1 - P.t0) * aw;
    P.py = (v) => PM.t + (hi - v) / (hi - lo) * ah;
    const L = layer(f.w, f.h, f.dpr);
    const g = L.g;
    g.fillStyle = '#fff'; g.fillRect(0, 0, f.w, f.h);
    g.font = FONT; g.lineWidth = 1;
    const xt = niceTicks(P.t0, P.t1, Math.max(3, Math.floor(aw / 60)));
    const yt = niceTicks(lo, hi, Math.max(3, Math.floor(ah / 34)));
    g.strokeStyle = C.grid;
    for (const t of xt) { g.beginPath(); g.moveTo(P.px(t), PM.t); g.lineTo(P.px(t), PM.t + ah); g.stroke(); }
    for (const v of yt) { g.beginPath(); g.moveTo(PM.l, P.py(v)); g.lineTo(PM.l + aw, P.py(v)); g.stroke(); }
    // undefined stretches (a null in every series), shaded
    g.fillStyle = 'rgba(192,57,43,0.12)';
    for (let i = 0; i < N; i++) {
      if (P.series.every((s) => s.col[i] === null)) {
        const a = P.px(S.t[Math.max(0, i - 1)]), b = P.px(S.t[Math.min(N - 1, i + 1)]);
        g.fillRect(a, PM.t, Math.max(1, b - a), ah);
      }
    }
    if (P.zero) {
      g.strokeStyle = 'rgba(192,57,43,0.8)'; g.setLineDash([5, 4]);
      g.beginPath(); g.moveTo(PM.l, P.py(0)); g.lineTo(PM.l + aw, P.py(0)); g.stroke(); g.setLineDash([]);
    }
    // re-plans and obstacle appearances as thin vertical marks
    g.lineWidth = 1;
    for (let i = 1; i < D.plans.length; i++) {
      const x = P.px(D.plans[i].t);
      g.strokeStyle = 'rgba(142,68,173,0.7)'; g.setLineDash([3, 3]);
      g.beginPath(); g.moveTo(x, PM.t); g.lineTo(x, PM.t + ah); g.stroke();
    }
    for (const o of D.obstacles) {
      const x = P.px(o.t);
      g.strokeStyle = 'rgba(255,140,26,0.85)'; g.setLineDash([1, 3]);
      g.beginPath(); g.moveTo(x, PM.t); g.lineTo(x, PM.t + ah); g.stroke();
    }
    g.setLineDash([]);
    g.strokeStyle = C.axis; g.strokeRect(PM.l + 0.5, PM.t + 0.5, aw, ah);
    g.fillStyle = C.text; g.textAlign = 'center'; g.textBaseline = 'top';
    for (const t of xt) g.fillText(fmt(t), P.px(t), PM.t + ah + 4);
    g.textAlign = 'right';
    g.fillText('t [s]', PM.l + aw, PM.t + ah + 17);
    g.textBaseline = 'middle';
    for (const v of yt) g.fillText(fmt(v), PM.l - 5, P.py(v));
    g.save();
    g.beginPath(); g.rect(PM.l, PM.t, aw, ah); g.clip();
    g.lineJoin = 'round';
    for (const s of P.series) {
      g.beginPath();
      let pen = false;
      for (let i = 0; i < N; i++) {
        const v = s.col[i];
        if (v === null || !isFinite(v)) { pen = false; continue; }
        if (pen) g.lineTo(P.px(S.t[i]), P.py(v)); else { g.moveTo(P.px(S.t[i]), P.py(v)); pen = true; }
      }
      g.strokeStyle = s.colour; g.lineWidth = s.dash ? 1.5 : 1.8;
      g.setLineDash(s.dash ? [6, 4] : []);
      g.stroke();
    }
    g.restore();
    P.layer = L.c;
    if (!P.counted) { P.counted = true; plotsDrawn++; body.dataset.plotsDrawn = String(plotsDrawn); }
  }
  function drawPlot(P, time, frame) {
    if (!P.layer) buildPlotStatic(P);
    const g = P.f.g;
    g.clearRect(0, 0, P.w, P.h);
    g.drawImage(P.layer, 0, 0, P.w, P.h);
    const x = P.px(time);
    g.strokeStyle = '#111'; g.lineWidth = 1.2;
    g.beginPath(); g.moveTo(x, PM.t); g.lineTo(x, P.h - PM.b); g.stroke();
    for (const s of P.series) {
      const v = N ? s.col[frame] : null;
      s.value.textContent = fmt(v);
      if (v === null || !isFinite(v)) continue;
      disk(g, P.px(S.t[frame]), P.py(v), 3.5);
      g.fillStyle = s.colour; g.fill();
    }
  }

  // ---------- tables ----------
  // every summary.json key with a human label and its unit ('' for none); a key the page
  // does not know is shown as it is, so no value is ever hidden
  const LABELS = {
    mission: ['mission', ''], reached: ['goal reached', ''], reason: ['why not', ''],
    time_to_goal: ['time to goal', 's'], simulated_time: ['simulated time', 's'],
    replans: ['re-plans', ''], min_zmp_margin: ['smallest ZMP margin', 'm'],
    min_force_angle: ['smallest Force-Angle measure', 'rad'],
    min_moment_height: ['smallest Moment-Height measure', ''],
    min_clearance: ['smallest clearance', 'm'], max_tracking_error: ['largest tracking error', 'm'],
    final_pose_error: ['final pose error (position, heading)', 'm, rad'],
    end_effector_error: ['end-effector error', 'm'], max_slip_ratio: ['largest wheel slip ratio', ''],
    torque_saturated_steps: ['control steps at a torque limit', ''],
    speed_saturated_steps: ['control steps at a speed limit', ''], control_steps: ['control steps', ''],
    actuator_energy: ['actuator energy ∫Σ|τ q̇| dt', 'J'], input_work: ['net input work', 'J'],
    'tip_over_limits.forward': ['tip-over acceleration limit, forward', 'm/s²'],
    'tip_over_limits.backward': ['tip-over acceleration limit, backward', 'm/s²'],
    'tip_over_limits.left': ['tip-over acceleration limit, left', 'm/s²'],
    'tip_over_limits.right': ['tip-over acceleration limit, right', 'm/s²'],
    timing_acceleration: ['accelerations of the timing (forward, backward)', 'm/s²'],
    samples: ['recorded samples', ''], wall_time_s: ['wall time, total', 's'],
    'wall_time.planning_s': ['wall time, planning', 's'],
    'wall_time.smoothing_timing_s': ['wall time, smoothing and timing', 's'],
    'wall_time.simulation_s': ['wall time, simulation', 's'],
    'wall_time.report_s': ['wall time, report', 's'],
    real_time_factor: ['real-time factor (simulated / wall time)', ''],
    files: ['files written', ''], replan_timing: ['re-plan timing', ''],
    'footprint.source': ['footprint from', ''], 'footprint.radius': ['footprint radius (C-space disk)', 'm'],
    'footprint.posture': ['footprint posture', ''],
    'footprint.circumscribed': ['footprint polygon, circumscribed radius', 'm'],
    'footprint.padding': ['footprint padding', 'm'], 'footprint.polygon': ['footprint polygon (base frame x, y)', 'm'],
  };
  function cellText(v) {
    if (v === null || v === undefined) return '—';
    if (typeof v === 'number') return fmt(v, 5);
    if (typeof v === 'boolean') return v ? 'yes' : 'no';
    if (Array.isArray(v)) return v.map(cellText).join(', ');
    if (typeof v === 'object') return Object.keys(v).map(function (k) { return k + ' ' + cellText(v[k]); }).join(', ');
    return String(v);
  }
  // one re-plan's timing as a sentence (summary.json's replan_timing entries)
  function replanText(p) {
    return 't = ' + fmt(p.t) + ' s (' + p.trigger + '): D* Lite ' + fmt(p.dstar_lite_ms, 3) + ' ms, ' +
      p.expanded + ' cells expanded; smoothing and timing ' + fmt(p.smoothing_timing_ms, 3) + ' ms; ' +
      fmt(p.duration) + ' s to go from ' + fmt(p.v_start) + ' m/s';
  }
  function summaryTable() {
    const tab = document.getElementById('summary');
    function row(label, text, cls) {
      const tr = el('tr');
      tr.appendChild(el('th', null, label));
      const td = el('td', null, text);
      if (cls) td.className = cls;
      tr.appendChild(td);
      tab.appendChild(tr);
    }
    function rows(obj, prefix) {
      for (const k of Object.keys(obj)) {
        const v = obj[k];
        const name = prefix + k;
        if (v && typeof v === 'object' && !Array.isArray(v)) { rows(v, name + '.'); continue; }
        const lu = LABELS[name] || [name, ''];
        const label = lu[0] + (lu[1] ? ' [' + lu[1] + ']' : '');
        if (name === 'replan_timing' && Array.isArray(v)) {
          if (!v.length) row(label, 'none');
          v.forEach(function (p, i) { row('re-plan ' + (i + 1), replanText(p)); });
          continue;
        }
        row(label, cellText(v), typeof v === 'boolean' ? (v ? 'yes' : 'no') : null);
      }
    }
    if (D.summary && typeof D.summary === 'object' && !Array.isArray(D.summary)) {
      // the headline fields first, in reading order, then the rest as they come
      const first = ['reached', 'reason', 'time_to_goal', 'replans', 'min_zmp_margin', 'min_clearance',
        'max_tracking_error', 'final_pose_error', 'end_effector_error', 'wall_time_s'];
      const ordered = {};
      for (const k of first) if (k in D.summary) ordered[k] = D.summary[k];
      for (const k of Object.keys(D.summary)) if (!(k in ordered)) ordered[k] = D.summary[k];
      rows(ordered, '');
    }
    const st = document.getElementById('status');
    const sm = D.summary || {};
    if (sm.reached === true) { st.className = 'good'; st.textContent = 'goal reached' + (typeof sm.time_to_goal === 'number' ? ' in ' + fmt(sm.time_to_goal) + ' s' : ''); }
    else if (sm.reached === false) { st.className = 'bad'; st.textContent = 'not reached' + (sm.reason ? ': ' + sm.reason : ''); }
    else st.style.display = 'none';
  }
  const eventRows = [];
  function eventsTable() {
    const tab = document.getElementById('events');
    const head = el('tr');
    head.appendChild(el('th', null, 't [s]'));
    head.appendChild(el('th', null, 'kind'));
    head.appendChild(el('th', null, 'what happened'));
    tab.appendChild(head);
    D.events.forEach(function (e) {
      const tr = el('tr');
      tr.appendChild(el('td', null, fmt(e.t)));
      const k = el('td');
      k.appendChild(el('span', { class: 'kind' }, e.kind));
      tr.appendChild(k);
      tr.appendChild(el('td', null, e.text));
      tr.addEventListener('click', function () { seek(e.t); });
      tab.appendChild(tr);
      eventRows.push({ tr: tr, t: e.t });
    });
    if (!D.events.length) { const tr = el('tr'); tr.appendChild(el('td', { colspan: '3' }, 'no events')); tab.appendChild(tr); }
  }
  const NOW = [
    ['t', 's', () => clock], ['x', 'm', (i, p) => p.x], ['y', 'm', (i, p) => p.y], ['θ', 'rad', (i, p) => p.th],
    ['v', 'm/s', (i) => S.v[i]], ['ω', 'rad/s', (i) => S.w[i]], ['ZMP margin', 'm', (i) => S.zmp[i]],
    ['FA minimum', 'rad', (i) => S.fa[i]], ['clearance', 'm', (i) => S.clr[i]], ['tracking error', 'm', (i) => S.err[i]],
    ['plan in use', '', () => { const k = activePlan(clock); return k < 0 ? null : k === 0 ? 'initial' : 're-plan ' + k; }],
  ];
  const nowCells = [];
  function nowTable() {
    const tab = document.getElementById('now');
    for (const r of NOW) {
      const tr = el('tr');
      tr.appendChild(el('th', null, r[0] + (r[1] ? ' [' + r[1] + ']' : '')));
      const td = el('td', null, '—');
      tr.appendChild(td);
      tab.appendChild(tr);
      nowCells.push(td);
    }
  }
  function updateTables(frame) {
    const p = poseAt(clock);
    NOW.forEach(function (r, i) {
      const v = N ? r[2](frame, p) : null;
      nowCells[i].textContent = typeof v === 'string' ? v : fmt(v);
    });
    let cur = -1;
    eventRows.forEach(function (e, i) { if (e.t <= clock + 1e-9) cur = i; });
    eventRows.forEach(function (e, i) {
      e.tr.className = i === cur ? 'current' : e.t > clock + 1e-9 ? 'future' : '';
    });
  }

  // ---------- the clock ----------
  let clock = T0, playing = true, speed = 1, last = performance.now();
  const playBtn = document.getElementById('play');
  const slider = document.getElementById('slider');
  const clockText = document.getElementById('clock');
  const speedSel = document.getElementById('speed');
  function draw() {
    const frame = frameAt(clock);
    try {
      drawTop(clock, frame);
      drawSide(clock, frame);
      if (view3d) view3d.draw(clock);
      for (const P of PLOTS) drawPlot(P, clock, frame);
      updateTables(frame);
    } finally {
      body.dataset.frame = String(frame);
      body.dataset.time = clock.toFixed(3);
      clockText.textContent = 't = ' + clock.toFixed(2) + ' s / ' + T1.toFixed(2) + ' s';
      if (T1 > T0) slider.value = String(Math.round(1000 * (clock - T0) / (T1 - T0)));
    }
  }
  function seek(t) {
    clock = Math.min(T1, Math.max(T0, t));
    draw();
  }
  function setPlaying(p) {
    playing = p;
    if (p && clock >= T1) clock = T0;
    playBtn.textContent = p ? 'Pause' : clock >= T1 ? 'Replay' : 'Play';
    last = performance.now();
    body.dataset.playing = p ? '1' : '0';
  }
  playBtn.addEventListener('click', function () { setPlaying(!playing); });
  slider.addEventListener('input', function () { seek(T0 + (T1 - T0) * Number(slider.value) / 1000); });
  speedSel.addEventListener('change', function () { speed = Number(speedSel.value) || 1; });
  document.addEventListener('keydown', function (ev) {
    if (ev.target && (ev.target.tagName === 'INPUT' || ev.target.tagName === 'SELECT')) return;
    if (ev.key === ' ') { ev.preventDefault(); setPlaying(!playing); }
    else if (ev.key === 'ArrowRight') seek(clock + 0.02 * (T1 - T0));
    else if (ev.key === 'ArrowLeft') seek(clock - 0.02 * (T1 - T0));
  });
  let resizeTimer = null;
  window.addEventListener('resize', function () {
    clearTimeout(resizeTimer);
    resizeTimer = setTimeout(function () {
      buildTopStatic(); buildSideStatic();
      for (const P of PLOTS) buildPlotStatic(P);
      draw();
    }, 120);
  });
  // A timer, not requestAnimationFrame, drives the clock: headless browsers run timers in
  // virtual time, so the page plays in a test as it does on screen.
  function tick() {
    const now = performance.now();
    if (playing) {
      clock += speed * (now - last) / 1000;
      if (clock >= T1) { clock = T1; setPlaying(false); }
      draw();
    }
    last = now;
  }

  // the 3-D view (view3d.js), when the browser has WebGL
  const view3d = window.momaView3d(D, document.getElementById('view3d'),
    document.getElementById('view3d-note'), poseAt);
  topLegend();
  sideLegend();
  setupPlots();
  summaryTable();
  eventsTable();
  nowTable();
  body.dataset.playing = '1';
  if (N < 2) setPlaying(false);
  draw();
  setInterval(tick, 40);
})();
