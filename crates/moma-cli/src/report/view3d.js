// The mission report's 3-D view (three.js, bundled before this script as the global
// THREE): the map as the ground with its occupied cells raised as walls, the obstacles
// appearing at their times, the executed path, the end-effector target, a scene's
// objects, and the robot's shapes on its bodies, placed from the poses moma's forward
// kinematics computed (interpolated between frames). The page's clock calls draw(time).
// Mouse: drag to orbit, wheel to zoom, right-drag or shift-drag to pan, double-click to
// reset. State for headless checks on <body>: data-view3d ("drawn", "no-webgl", "none"),
// data-view3d-shapes, data-view3d-rect (the canvas in page pixels: x,y,w,h).
window.momaView3d = function (D, canvas, note, poseAt) {
  'use strict';
  const body = document.body;
  const V = D.view3d;
  const probe = document.createElement('canvas');
  if (!(probe.getContext('webgl2') || probe.getContext('webgl'))) {
    note.textContent = 'The 3-D view needs WebGL, which this browser does not offer.';
    body.dataset.view3d = 'no-webgl';
    return null;
  }
  const COL = {
    bg: 0xeef2f6, wall: 0x7a8494, obstacle: 0xff8c1a, path: 0xd62728, plan: 0x8a94a6,
    target: 0xe6007e, scene: 0xc8a165, robot: [0x2a9d8f, 0x1f7a6f], wheel: 0x33414d,
  };
  const renderer = new THREE.WebGLRenderer({ canvas: canvas, antialias: true, preserveDrawingBuffer: true });
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(COL.bg);
  const camera = new THREE.PerspectiveCamera(45, 2, 0.02, 500);
  camera.up.set(0, 0, 1);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(3, -4, 8);
  scene.add(sun);

  // ---------- the map: ground image and walls ----------
  const M = D.map;
  if (M.png && M.x1 > M.x0 && M.y1 > M.y0) {
    const tex = new THREE.Texture();
    tex.magFilter = THREE.NearestFilter;
    tex.colorSpace = THREE.SRGBColorSpace;
    const img = new Image();
    img.onload = function () { tex.image = img; tex.needsUpdate = true; render(); };
    img.src = M.png;
    const ground = new THREE.Mesh(
      new THREE.PlaneGeometry(M.x1 - M.x0, M.y1 - M.y0),
      new THREE.MeshBasicMaterial({ map: tex, color: 0xffffff }));
    ground.position.set((M.x0 + M.x1) / 2, (M.y0 + M.y1) / 2, -0.002);
    scene.add(ground);
  }
  const WALL_H = 0.5;
  if (D.walls && D.walls.length) {
    const pos = [], nor = [];
    // one box per rectangle: six faces of two triangles, outward normals
    const faces = [
      [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, -1]],
      [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1], [0, 0, 1]],
      [[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0], [0, -1, 0]],
      [[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1], [0, 1, 0]],
      [[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1], [-1, 0, 0]],
      [[1, 0, 0], [1, 0, 1], [1, 1, 1], [1, 1, 0], [1, 0, 0]],
    ];
    for (const w of D.walls) {
      const X = [w[0], w[2]], Y = [w[1], w[3]], Z = [0, WALL_H];
      for (const f of faces) {
        const c = f.slice(0, 4).map(function (k) { return [X[k[0]], Y[k[1]], Z[k[2]]]; });
        for (const i of [0, 2, 1, 0, 3, 2]) { pos.push(c[i][0], c[i][1], c[i][2]); nor.push(f[4][0], f[4][1], f[4][2]); }
      }
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
    g.setAttribute('normal', new THREE.Float32BufferAttribute(nor, 3));
    scene.add(new THREE.Mesh(g, new THREE.MeshLambertMaterial({ color: COL.wall })));
  }

  // ---------- obstacles, paths, target ----------
  const obstacles = D.obstacles.map(function (o) {
    const m = new THREE.Mesh(urdfCylinder(o.r, 1.0), new THREE.MeshLambertMaterial({ color: COL.obstacle }));
    m.position.set(o.c[0], o.c[1], 0.5);
    m.visible = false;
    scene.add(m);
    return { t: o.t, mesh: m };
  });
  function line(xy, z, colour) {
    const p = [];
    for (let i = 0; i + 1 < xy.length; i += 2) p.push(xy[i], xy[i + 1], z);
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(p, 3));
    const l = new THREE.Line(g, new THREE.LineBasicMaterial({ color: colour }));
    scene.add(l);
    return l;
  }
  const plans = D.plans.map(function (p) { return { t: p.t, line: line(p.p, 0.01, COL.plan) }; });
  const S = D.samples;
  const trail = [];
  for (let i = 0; i < S.t.length; i++) trail.push(S.x[i], S.y[i]);
  const path = line(trail, 0.02, COL.path);
  if (D.ee_target) {
    const m = new THREE.Mesh(new THREE.SphereGeometry(0.04, 16, 12), new THREE.MeshLambertMaterial({ color: COL.target }));
    m.position.set(D.ee_target[0], D.ee_target[1], D.ee_target[2]);
    scene.add(m);
  }

  // ---------- shapes ----------
  function urdfCylinder(r, l) { const g = new THREE.CylinderGeometry(r, r, l, 32); g.rotateX(Math.PI / 2); return g; }
  function decode(b64) {
    const s = atob(b64);
    const u = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
    return new DataView(u.buffer);
  }
  function meshGeometry(g) {
    const dv = decode(g.v), fv = decode(g.f);
    const n = dv.byteLength / 6, b = g.box;
    const pos = new Float32Array(3 * n);
    for (let i = 0; i < 3 * n; i++) {
      const a = i % 3;
      pos[i] = b[a] + (b[a + 3] - b[a]) * dv.getUint16(2 * i, true) / 65535;
    }
    const w = g.wide ? 4 : 2, m = fv.byteLength / w;
    const idx = g.wide ? new Uint32Array(m) : new Uint16Array(m);
    for (let i = 0; i < m; i++) idx[i] = g.wide ? fv.getUint32(4 * i, true) : fv.getUint16(2 * i, true);
    // flat shading: every triangle its own vertices, so normals follow the faces
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geo.setIndex(new THREE.BufferAttribute(idx, 1));
    const flat = geo.toNonIndexed();
    flat.computeVertexNormals();
    return flat;
  }
  function geometry(g) {
    if (g.type === 'box') return new THREE.BoxGeometry(g.size[0], g.size[1], g.size[2]);
    if (g.type === 'cylinder') return urdfCylinder(g.r, g.l);
    if (g.type === 'sphere') return new THREE.SphereGeometry(g.r, 24, 16);
    if (g.type === 'capsule') { const c = new THREE.CapsuleGeometry(g.r, g.l, 8, 24); c.rotateX(Math.PI / 2); return c; }
    return meshGeometry(g);
  }
  function place(obj, p) {
    obj.position.set(p[0], p[1], p[2]);
    obj.quaternion.set(p[3], p[4], p[5], p[6]);
  }
  const bodies = [];
  let shapes = 0;
  if (V) {
    for (let b = 0; b < V.bodies.length; b++) {
      const grp = new THREE.Group();
      scene.add(grp);
      bodies.push(grp);
    }
    V.robot.forEach(function (s) {
      const wheel = /wheel/i.test(s.name);
      const colour = wheel ? COL.wheel : COL.robot[s.b % 2];
      const m = new THREE.Mesh(geometry(s.g), new THREE.MeshLambertMaterial({ color: colour }));
      place(m, s.p);
      bodies[s.b].add(m);
      shapes++;
    });
    V.scene.forEach(function (s) {
      const m = new THREE.Mesh(geometry(s.g), new THREE.MeshLambertMaterial({ color: COL.scene }));
      place(m, s.p);
      scene.add(m);
      shapes++;
    });
  }
  body.dataset.view3dShapes = String(shapes);
  if (!V) note.textContent = 'No robot geometry in this report: the map, obstacles and paths only.';

  // the bodies' poses at `time`: between the two frames around it, positions linear,
  // orientations along the shorter arc
  const qa = new THREE.Quaternion(), qb = new THREE.Quaternion();
  function poseBodies(time) {
    if (!V || !V.t.length) return;
    const T = V.t, nb = V.bodies.length, P = V.poses;
    let i = 0;
    if (time >= T[T.length - 1]) i = T.length - 1;
    else if (time > T[0]) { let lo = 0, hi = T.length - 1; while (hi - lo > 1) { const m = (lo + hi) >> 1; if (T[m] <= time) lo = m; else hi = m; } i = lo; }
    const j = Math.min(i + 1, T.length - 1);
    const f = T[j] > T[i] ? Math.min(1, Math.max(0, (time - T[i]) / (T[j] - T[i]))) : 0;
    for (let b = 0; b < nb; b++) {
      const a = 7 * (i * nb + b), c = 7 * (j * nb + b);
      const g = bodies[b];
      g.position.set(
        (P[a] + f * (P[c] - P[a])) / 1e3,
        (P[a + 1] + f * (P[c + 1] - P[a + 1])) / 1e3,
        (P[a + 2] + f * (P[c + 2] - P[a + 2])) / 1e3);
      qa.set(P[a + 3], P[a + 4], P[a + 5], P[a + 6]).normalize();
      qb.set(P[c + 3], P[c + 4], P[c + 5], P[c + 6]).normalize();
      g.quaternion.slerpQuaternions(qa, qb, f);
    }
  }

  // ---------- camera: orbit about the robot (or a fixed point) ----------
  const follow = document.getElementById('view3d-follow');
  const HOME = { az: -2.2, el: 0.5, dist: 4.5 };
  const cam = { az: HOME.az, el: HOME.el, dist: HOME.dist, pan: new THREE.Vector3(), fixed: new THREE.Vector3() };
  let lastTime = D.samples.t.length ? D.samples.t[0] : 0;
  function focus() {
    if (follow && !follow.checked) return cam.fixed.clone().add(cam.pan);
    // the first body (the robot's root) once posed, else the report's base pose
    if (bodies.length && V.t.length) return bodies[0].position.clone().setZ(bodies[0].position.z + 0.5).add(cam.pan);
    const p = poseAt(lastTime);
    return new THREE.Vector3(p.x, p.y, 0.5).add(cam.pan);
  }
  function placeCamera() {
    const c = focus();
    const ce = Math.cos(cam.el);
    camera.position.set(
      c.x + cam.dist * ce * Math.cos(cam.az),
      c.y + cam.dist * ce * Math.sin(cam.az),
      c.z + cam.dist * Math.sin(cam.el));
    camera.lookAt(c);
  }
  let drag = null;
  canvas.addEventListener('contextmenu', function (ev) { ev.preventDefault(); });
  canvas.addEventListener('mousedown', function (ev) {
    drag = { x: ev.clientX, y: ev.clientY, pan: ev.button === 2 || ev.shiftKey };
    ev.preventDefault();
  });
  window.addEventListener('mouseup', function () { drag = null; });
  window.addEventListener('mousemove', function (ev) {
    if (!drag) return;
    const dx = ev.clientX - drag.x, dy = ev.clientY - drag.y;
    drag.x = ev.clientX; drag.y = ev.clientY;
    if (drag.pan) {
      // move the focus in the ground plane, screen-aligned, scaled by the distance
      const k = cam.dist / canvas.clientHeight;
      const sx = Math.sin(cam.az), cx = Math.cos(cam.az);
      cam.pan.x += k * (dx * sx + dy * cx);
      cam.pan.y += k * (-dx * cx + dy * sx);
    } else {
      cam.az -= 0.008 * dx;
      cam.el = Math.min(1.5, Math.max(0.05, cam.el + 0.008 * dy));
    }
    render();
  });
  canvas.addEventListener('wheel', function (ev) {
    ev.preventDefault();
    cam.dist = Math.min(200, Math.max(0.3, cam.dist * Math.exp(0.0015 * ev.deltaY)));
    render();
  }, { passive: false });
  canvas.addEventListener('dblclick', function () {
    cam.az = HOME.az; cam.el = HOME.el; cam.dist = HOME.dist; cam.pan.set(0, 0, 0);
    render();
  });
  if (follow) {
    follow.addEventListener('change', function () {
      follow.checked = !follow.checked;
      const here = focus();
      follow.checked = !follow.checked;
      cam.fixed.copy(here);
      cam.pan.set(0, 0, 0);
      render();
    });
  }

  // ---------- size and drawing ----------
  let size = { w: 0, h: 0 };
  function resize() {
    const w = Math.max(200, canvas.clientWidth || canvas.parentNode.clientWidth || 400);
    const h = Math.round(w * 0.42);
    canvas.style.height = h + 'px';
    renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    size = { w: w, h: h };
  }
  function render() {
    placeCamera();
    renderer.render(scene, camera);
    const r = canvas.getBoundingClientRect();
    body.dataset.view3dRect = [r.left + window.scrollX, r.top + window.scrollY, r.width, r.height].map(Math.round).join(',');
    body.dataset.view3d = V ? 'drawn' : 'none';
  }
  function draw(time) {
    lastTime = time;
    poseBodies(time);
    for (const o of obstacles) o.mesh.visible = time >= o.t;
    let active = -1;
    plans.forEach(function (p, k) { if (p.t <= time + 1e-9) active = k; });
    plans.forEach(function (p, k) { p.line.visible = k === active; });
    let n = 0;
    while (n < S.t.length && S.t[n] <= time) n++;
    path.geometry.setDrawRange(0, Math.max(n, 1));
    render();
  }
  resize();
  window.addEventListener('resize', function () { resize(); render(); });
  return { draw: draw, size: function () { return size; } };
};
