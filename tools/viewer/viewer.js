// The screwfem viewer (inlined into the page by tools/screwfem_view.py; three.js r111).
//
// The run's data (element #run-data, written by screwfem_view.py from the ParaView frames)
// holds every drawn point's position at the first frame and, for the points that move, at
// every frame; the orientations (quaternions) of the points that carry a frame (rod sections,
// boxes, joints, planes); the constant sizes (radius, half sizes); what the cells are (rods,
// rigid bodies' links, contact shapes and inertia boxes, joints, tendons and force elements
// with their tensions, contact points with their forces, obstacles); the rods' colour fields
// and the recorded points (points.csv). Between frames positions, tensions and forces are
// interpolated linearly and orientations by normalised linear interpolation.
//
// Drawn true to size: rods as tubes of their section (round or rectangular; a rod without a
// size in the frames thin, at 0.6 % of the mechanism), rigid bodies as their contact shapes or
// else the box of their inertia, obstacles. Markers whose size means nothing: joints
// (spheres), joint frames (x red, y green, z blue), links (thin rods from a body's frame to
// its joints), tendons and force elements (thin tubes coloured by tension), contact forces
// (arrows from the contact point along the force on the shape, drawn over everything);
// pressure chambers as see-through tubes of their area's circle inside the rods. A static
// run's time is its load factor (labelled lambda). A page served by Simulation.view (data.live)
// receives its frames over a WebSocket ("live view" below).
//
// URL parameters (for tests and links): t=SECONDS shows that time and stays paused;
// bare=1 draws the mechanism alone (no grid, axes, obstacles, trails, labels or controls);
// hide=a,b and show=a,b switch the layers (rods chambers bodies links joints frames tendons
// forces obstacles points grid labels); follow=NAME follows a body, rod, joint or recorded point;
// colour=FIELD colours the rods; labels=1; trail=SECONDS or all; speed=FACTOR;
// camera: view=front|back|left|right|top|bottom|iso, target=X,Y,Z, span=METRES (the width of
// the picture at the target), ortho=1 (orthographic), eye=X,Y,Z (perspective, from there);
// force_scale=METRES_PER_NEWTON (arrow length).
(function () {
  "use strict";

  var data = JSON.parse(document.getElementById("run-data").textContent);
  var params = new URLSearchParams(window.location.search);
  var bare = params.get("bare") === "1";
  if (bare) document.body.classList.add("bare");

  // ---- data --------------------------------------------------------------------------------
  function floats(b64) {
    if (!b64) return new Float32Array(0);
    var bytes = atob(b64), n = bytes.length, buf = new Uint8Array(n);
    for (var i = 0; i < n; ++i) buf[i] = bytes.charCodeAt(i);
    return new Float32Array(buf.buffer);
  }
  // A track of screwfem_view.py: 16-bit integers q, value = mid + q scale per component.
  function decode(t) {
    if (!t || !t.data) return new Float32Array(0);
    var bytes = atob(t.data), n = bytes.length >> 1, out = new Float32Array(n), nc = t.mid.length;
    for (var i = 0; i < n; ++i) {
      var q = bytes.charCodeAt(2 * i) | bytes.charCodeAt(2 * i + 1) << 8;
      if (q > 32767) q -= 65536;
      out[i] = t.mid[i % nc] + q * t.scale[i % nc];
    }
    return out;
  }
  function numberList(text) {
    if (!text) return null;
    var v = text.split(",").map(Number);
    return v.every(isFinite) ? v : null;
  }
  var times = data.times, nf = times.length, np = data.npoints;
  var x0 = floats(data.x0), moving = data.moving, track = decode(data.positions);
  var oriented = data.oriented, q0 = floats(data.q0), turning = data.turning, quats = decode(data.quats);
  var radius = floats(data.radius), half = floats(data.half);
  var tensionTrack = decode(data.tension), forceTrack = decode(data.forces);
  // Per contact and frame: slipping (1) or sticking (0), the anchor's deflection [m], the share
  // of static friction used (none in live pages and runs without the stick law's outputs).
  var stateTrack = data.contact_states ? decode(data.contact_states) : new Float32Array(0);
  var nm = moving.length, nt = turning.length, nl = data.lines.length, nc = data.contacts.length;
  var fieldPoints = data.field_points || [];
  var fields = data.fields.map(function (f) {
    var v = decode(f.values), lo = Infinity, hi = -Infinity;
    for (var i = 0; i < v.length; ++i) { if (v[i] < lo) lo = v[i]; if (v[i] > hi) hi = v[i]; }
    return { name: f.name, unit: f.unit, values: v, lo: lo, hi: hi > lo ? hi : lo + 1 };
  });
  var rec = data.recorded;
  var recXyz = rec ? decode(rec.xyz) : null, recTimes = rec ? rec.times : [];
  var t0 = nf ? times[0] : 0, t1 = nf ? times[nf - 1] : 0;

  // Current state: positions (np x 3), quaternions of the oriented points, tensions, forces,
  // the colour field on the field points.
  var cur = new Float32Array(x0), curQ = new Float32Array(q0);
  var curTension = new Float32Array(nl), curForce = new Float32Array(3 * nc);
  var curState = new Float32Array(3 * nc);
  var curField = new Float32Array(fieldPoints.length), field = null;
  var slot = new Int32Array(np).fill(-1);  // point -> its index in `oriented`
  oriented.forEach(function (p, k) { slot[p] = k; });
  var fieldSlot = new Int32Array(np).fill(-1);
  fieldPoints.forEach(function (p, k) { fieldSlot[p] = k; });

  // Index k and weight w with t between times[k] and times[k+1] (w in [0, 1]).
  function bracket(ts, t) {
    if (ts.length < 2 || t <= ts[0]) return [0, 0];
    if (t >= ts[ts.length - 1]) return [ts.length - 1, 0];
    var lo = 0, hi = ts.length - 1;
    while (hi - lo > 1) { var mid = (lo + hi) >> 1; if (ts[mid] <= t) lo = mid; else hi = mid; }
    return [lo, (t - ts[lo]) / (ts[lo + 1] - ts[lo])];
  }
  function lerp(src, stride, k, w, i) {
    var a = src[k * stride + i];
    return w > 0 ? a + w * (src[(k + 1) * stride + i] - a) : a;
  }
  function computeState(t) {
    var kw = bracket(times, t), k = kw[0], w = kw[1], i, c;
    for (i = 0; i < nm; ++i)
      for (c = 0; c < 3; ++c) cur[3 * moving[i] + c] = lerp(track, 3 * nm, k, w, 3 * i + c);
    for (i = 0; i < nt; ++i) {
      var o = 4 * turning[i], n2 = 0;
      for (c = 0; c < 4; ++c) { curQ[o + c] = lerp(quats, 4 * nt, k, w, 4 * i + c); n2 += curQ[o + c] * curQ[o + c]; }
      var s = n2 > 0 ? 1 / Math.sqrt(n2) : 1;
      for (c = 0; c < 4; ++c) curQ[o + c] *= s;
    }
    for (i = 0; i < nl; ++i) curTension[i] = lerp(tensionTrack, nl, k, w, i);
    for (i = 0; i < 3 * nc && forceTrack.length; ++i) curForce[i] = lerp(forceTrack, 3 * nc, k, w, i);
    if (stateTrack.length >= 3 * nc * nf)
      for (i = 0; i < 3 * nc; ++i) curState[i] = lerp(stateTrack, 3 * nc, k, w, i);
    if (field) for (i = 0; i < fieldPoints.length; ++i) curField[i] = lerp(field.values, fieldPoints.length, k, w, i);
  }
  function point(i) { return new THREE.Vector3(cur[3 * i], cur[3 * i + 1], cur[3 * i + 2]); }
  function quaternion(i) {
    var o = 4 * slot[i];
    return slot[i] < 0 ? new THREE.Quaternion() : new THREE.Quaternion(curQ[o], curQ[o + 1], curQ[o + 2], curQ[o + 3]);
  }
  // Column a of point i's frame (x, y, z axis).
  function axis(i, a) {
    if (slot[i] < 0) return new THREE.Vector3(a === 0 ? 1 : 0, a === 1 ? 1 : 0, a === 2 ? 1 : 0);
    var o = 4 * slot[i], x = curQ[o], y = curQ[o + 1], z = curQ[o + 2], w = curQ[o + 3];
    if (a === 0) return new THREE.Vector3(1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w));
    if (a === 1) return new THREE.Vector3(2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w));
    return new THREE.Vector3(2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y));
  }
  function halfSize(i) { return new THREE.Vector3(half[3 * i], half[3 * i + 1], half[3 * i + 2]); }

  // Bounding box of the mechanism's whole motion (every frame, the points' sizes and the
  // recorded points; not the obstacles, which may reach far): sizes and framing.
  var isObstacle = new Uint8Array(np);
  data.obstacles.forEach(function (o) { o.points.forEach(function (p) { isObstacle[p] = 1; }); });
  var box = new THREE.Box3(), box0 = new THREE.Box3(), v3 = new THREE.Vector3();
  function expand(b, x, y, z, r) {
    b.expandByPoint(v3.set(x - r, y - r, z - r));
    b.expandByPoint(v3.set(x + r, y + r, z + r));
  }
  var isMoving = new Int32Array(np).fill(-1);
  moving.forEach(function (p, k) { isMoving[p] = k; });
  for (var i = 0; i < np; ++i) {
    if (isObstacle[i]) continue;
    var r = radius[i] || 0;
    expand(box0, x0[3 * i], x0[3 * i + 1], x0[3 * i + 2], r);
    if (isMoving[i] < 0) continue;
    for (var f = 0; f < nf; ++f) {
      var o = 3 * (f * nm + isMoving[i]);
      expand(box, track[o], track[o + 1], track[o + 2], r);
    }
  }
  box.union(box0);
  if (recXyz)
    for (i = 0; i + 2 < recXyz.length; i += 3) box.expandByPoint(v3.set(recXyz[i], recXyz[i + 1], recXyz[i + 2]));
  if (box.isEmpty()) box.set(new THREE.Vector3(-0.5, -0.5, -0.5), new THREE.Vector3(0.5, 0.5, 0.5));
  var size = Math.max(box.getSize(new THREE.Vector3()).length(), 1e-6);
  // The mechanism's own size (its initial bounding box) sets the markers' sizes and the
  // following camera's distance; the motion's size (box) sets the grid and the overall view.
  var size0 = box0.isEmpty() ? size : Math.max(box0.getSize(new THREE.Vector3()).length(), 1e-3 * size);
  var thinRadius = 0.006 * size0, jointRadius = 0.012 * size0, lineRadius = 0.0015 * size0;
  var up = new THREE.Vector3().fromArray(data.up).normalize();

  // ---- layers --------------------------------------------------------------------------------
  var layerNames = ["rods", "chambers", "bodies", "links", "joints", "frames", "tendons", "forces",
                    "obstacles", "points", "grid", "labels"];
  var shown = { rods: true, chambers: true, bodies: true, links: true, joints: true, frames: false,
                tendons: true, forces: true, obstacles: !bare, points: !bare, grid: !bare, labels: false };
  if (params.get("labels") === "1") shown.labels = true;
  (params.get("hide") || "").split(",").forEach(function (n) { if (n in shown) shown[n] = false; });
  (params.get("show") || "").split(",").forEach(function (n) { if (n in shown) shown[n] = true; });
  var layers = {};
  layerNames.forEach(function (n) { layers[n] = new THREE.Group(); });

  // ---- renderer, camera, controls ----------------------------------------------------------
  var container = document.getElementById("view");
  var renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    window.screwfemReport("WebGL is not available in this browser: " + e.message);
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xf5f6f8, 1);
  container.appendChild(renderer.domElement);
  var scene = new THREE.Scene();
  layerNames.forEach(function (n) { scene.add(layers[n]); });
  var ortho = params.get("ortho") === "1";
  var camera = ortho ? new THREE.OrthographicCamera(-1, 1, 1, -1, size * 1e-3, size * 100)
                     : new THREE.PerspectiveCamera(35, 1, size * 1e-3, size * 100);
  camera.up.copy(up);
  var controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.enableDamping = false;
  controls.screenSpacePanning = true;
  var aspect = 1, orthoWidth = size;

  scene.add(new THREE.HemisphereLight(0xffffff, 0x8890a0, 0.75));
  var sun = new THREE.DirectionalLight(0xffffff, 0.65);
  sun.position.set(1, -1, 2);
  camera.add(sun);
  scene.add(camera);

  // World directions for the named views: side (x without its up part), depth = up x side.
  var side = new THREE.Vector3(1, 0, 0);
  if (Math.abs(side.dot(up)) > 0.9) side.set(0, 1, 0);
  side.sub(up.clone().multiplyScalar(side.dot(up))).normalize();
  var depth = new THREE.Vector3().crossVectors(up, side);  // side x depth = up
  // The direction from the target to the camera and the screen's up for a named view.
  function viewDirection(name) {
    var dirs = {
      front: [depth.clone().negate(), up], back: [depth.clone(), up], right: [side.clone(), up],
      left: [side.clone().negate(), up], top: [up.clone(), depth], bottom: [up.clone().negate(), depth.clone().negate()],
    };
    if (dirs[name]) return dirs[name];
    return [side.clone().multiplyScalar(0.55).addScaledVector(depth, -0.8).addScaledVector(up, 0.5).normalize(), up];
  }

  function setProjection(width) {
    if (ortho) {
      orthoWidth = width;
      camera.left = -width / 2; camera.right = width / 2;
      camera.top = width / 2 / aspect; camera.bottom = -width / 2 / aspect;
      camera.zoom = 1;
    } else {
      camera.aspect = aspect;
    }
    camera.updateProjectionMatrix();
  }

  // Places the camera: the URL's view, target, span and eye, else the whole motion from the
  // front-right and above, from the nearest distance at which every corner of its bounding
  // box is in the picture.
  function frameAll(useUrl) {
    var named = viewDirection(useUrl ? params.get("view") : null);
    var dir = named[0].clone(), camUp = named[1].clone();
    var target = (useUrl && numberList(params.get("target"))) || null;
    var center = target ? new THREE.Vector3().fromArray(target) : box.getCenter(new THREE.Vector3());
    var eye = useUrl && !ortho && numberList(params.get("eye"));
    if (eye) dir = new THREE.Vector3().fromArray(eye).sub(center).normalize();
    var right = new THREE.Vector3().crossVectors(dir, camUp).negate().normalize();
    var screenUp = new THREE.Vector3().crossVectors(right, dir).negate().normalize();
    var span = useUrl ? Number(params.get("span")) : NaN;
    var tanV = Math.tan((ortho ? 35 : camera.fov) * Math.PI / 360), tanH = tanV * aspect;
    var dist = 0, width = 0;
    for (var c = 0; c < 8; ++c) {
      var corner = new THREE.Vector3(c & 1 ? box.max.x : box.min.x, c & 2 ? box.max.y : box.min.y,
                                     c & 4 ? box.max.z : box.min.z).sub(center);
      var along = corner.dot(dir);  // towards the camera
      dist = Math.max(dist, along + Math.abs(corner.dot(right)) / tanH,
                      along + Math.abs(corner.dot(screenUp)) / tanV);
      width = Math.max(width, 2 * Math.abs(corner.dot(right)), 2 * Math.abs(corner.dot(screenUp)) * aspect);
    }
    dist = Math.max(dist * 1.08, 1e-3 * size);
    if (span > 0) {
      width = span;
      if (!ortho) dist = span / 2 / tanH;
    } else {
      width *= 1.08;
    }
    camera.up.copy(camUp);
    controls.target.copy(center);
    if (eye) camera.position.fromArray(eye);
    else camera.position.copy(center).addScaledVector(dir, ortho ? Math.max(dist, size) : dist);
    var reach = camera.position.distanceTo(center) + size;
    camera.near = ortho ? 0 : Math.max(reach * 1e-4, 1e-6);
    camera.far = reach * 50;
    setProjection(width);
    controls.update();
  }

  // ---- ground grid and axes -----------------------------------------------------------------
  (function () {
    var floor = Math.min(0, box.min.dot(up));
    var extent = size * 1.1;
    var step = Math.pow(10, Math.floor(Math.log10(extent / 10)));
    if (extent / step > 40) step *= 5; else if (extent / step > 20) step *= 2;
    var divisions = Math.ceil(extent / step);
    var grid = new THREE.GridHelper(divisions * step, divisions, 0xa8b0bc, 0xd6dbe2);
    // GridHelper lies in its local x-z plane (normal +y): turn +y onto up.
    grid.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), up);
    var center = box.getCenter(new THREE.Vector3());
    center.sub(up.clone().multiplyScalar(center.dot(up)));
    center.set(Math.round(center.x / step) * step, Math.round(center.y / step) * step,
               Math.round(center.z / step) * step);
    center.add(up.clone().multiplyScalar(floor - 1e-4 * size));
    grid.position.copy(center);
    layers.grid.add(grid);
    var axesLen = Math.max(step, 0.12 * size);
    layers.grid.add(new THREE.AxesHelper(axesLen));
    ["x", "y", "z"].forEach(function (name, k) {
      var s = textSprite(name, ["#d0342c", "#2a9d3c", "#2c5fd0"][k], 0.035 * size);
      s.position.setComponent(k, axesLen * 1.08);
      layers.grid.add(s);
    });
  })();

  function textSprite(text, color, height) {
    var canvas = document.createElement("canvas"), ctx = canvas.getContext("2d");
    var px = 48;
    ctx.font = "600 " + px + "px sans-serif";
    canvas.width = Math.ceil(ctx.measureText(text).width) + 12;
    canvas.height = px + 12;
    ctx.font = "600 " + px + "px sans-serif";
    ctx.fillStyle = "rgba(255,255,255,0.75)";
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    ctx.fillStyle = color;
    ctx.textBaseline = "middle";
    ctx.fillText(text, 6, canvas.height / 2);
    var tex = new THREE.CanvasTexture(canvas);
    tex.minFilter = THREE.LinearFilter;
    var sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: tex, depthTest: false }));
    sprite.scale.set(height * canvas.width / canvas.height, height, 1);
    sprite.renderOrder = 10;
    return sprite;
  }

  // Turbo-like colour ramp, x in [0, 1].
  var ramp = [[0.19, 0.07, 0.23], [0.27, 0.53, 0.98], [0.10, 0.89, 0.71], [0.64, 0.99, 0.24],
              [0.98, 0.73, 0.22], [0.89, 0.27, 0.04], [0.48, 0.02, 0.01]];
  function colormap(x, out) {
    x = Math.min(Math.max(isFinite(x) ? x : 0, 0), 1) * (ramp.length - 1);
    var i = Math.min(Math.floor(x), ramp.length - 2), w = x - i;
    return out.setRGB(ramp[i][0] + w * (ramp[i + 1][0] - ramp[i][0]), ramp[i][1] + w * (ramp[i + 1][1] - ramp[i][1]),
                      ramp[i][2] + w * (ramp[i + 1][2] - ramp[i][2]));
  }

  // A mesh whose matrix the update sets (unit geometry scaled and placed).
  function placed(geometry, material, layer) {
    var m = new THREE.Mesh(geometry, material);
    m.matrixAutoUpdate = false;
    layer.add(m);
    return m;
  }
  var unitBox = new THREE.BoxBufferGeometry(1, 1, 1);
  var sphere = new THREE.SphereBufferGeometry(1, 24, 16);
  var cylinder = new THREE.CylinderBufferGeometry(1, 1, 1, 20, 1, true);  // along y, from -0.5 to 0.5
  var solidCylinder = new THREE.CylinderBufferGeometry(1, 1, 1, 32, 1, false);  // with flat ends
  var cone = new THREE.ConeBufferGeometry(1, 1, 16);
  var Y = new THREE.Vector3(0, 1, 0);
  // Sets m's matrix to a cylinder (or cone) of radius r from a to b.
  function between(m, a, b, r) {
    var d = b.clone().sub(a), len = d.length();
    var q = new THREE.Quaternion().setFromUnitVectors(Y, len > 0 ? d.clone().divideScalar(len) : Y);
    m.matrix.compose(a.clone().add(b).multiplyScalar(0.5), q, new THREE.Vector3(r, Math.max(len, 1e-12), r));
  }

  // ---- rods: tubes of their section through the node frames -----------------------------------
  var kSub = 6, kRadial = 20;
  var rodColor = new THREE.Color(0x2f7fc1);
  var unsized = false;
  // A tube through the points ids (a rod, or a chamber inside one), coloured by the field or
  // its colour.
  function makeTube(ids, layer, material, color, fielded) {
    var p0 = ids[0], round = true, sized = radius[p0] > 0;
    if (sized) round = Math.abs(half[3 * p0 + 1] - radius[p0]) <= 1e-9 * radius[p0] &&
                       Math.abs(half[3 * p0 + 2] - radius[p0]) <= 1e-9 * radius[p0];
    if (!sized) unsized = true;
    // The section's outline (u, v along the section's y and z half sizes) and its normals:
    // a circle, or a rectangle with its corners doubled for sharp edges.
    var prof = [];
    if (round) {
      for (var k = 0; k <= kRadial; ++k) {
        var a = 2 * Math.PI * k / kRadial;
        prof.push([Math.cos(a), Math.sin(a), Math.cos(a), Math.sin(a)]);
      }
    } else {
      [[1, -1, 1, 1, 1, 0], [1, 1, -1, 1, 0, 1], [-1, 1, -1, -1, -1, 0], [-1, -1, 1, -1, 0, -1]].forEach(function (e) {
        prof.push([e[0], e[1], e[4], e[5]], [e[2], e[3], e[4], e[5]]);
      });
    }
    var np_ = prof.length, rings = (ids.length - 1) * kSub + 1;
    var nv = rings * np_ + 2 * (np_ + 1);  // the side, then the two end caps (rim + centre)
    var geom = new THREE.BufferGeometry();
    var pos = new Float32Array(nv * 3), nor = new Float32Array(nv * 3), col = new Float32Array(nv * 3);
    geom.setAttribute("position", new THREE.BufferAttribute(pos, 3));
    geom.setAttribute("normal", new THREE.BufferAttribute(nor, 3));
    geom.setAttribute("color", new THREE.BufferAttribute(col, 3));
    var index = [];
    for (var r = 0; r + 1 < rings; ++r)
      for (var s = 0; s + 1 < np_; s += round ? 1 : 2) {
        var a0 = r * np_ + s, b0 = a0 + np_;
        index.push(a0, a0 + 1, b0, b0, a0 + 1, b0 + 1);
      }
    for (var cap = 0; cap < 2; ++cap) {
      var base = rings * np_ + cap * (np_ + 1), centre = base + np_;
      for (s = 0; s + 1 < np_; ++s)
        index.push.apply(index, cap ? [centre, base + s, base + s + 1] : [centre, base + s + 1, base + s]);
    }
    geom.setIndex(index);
    var mesh = new THREE.Mesh(geom, material);
    mesh.frustumCulled = false;
    layer.add(mesh);
    return { ids: ids, mesh: mesh, rings: rings, prof: prof, round: round, sized: sized, color: color,
             fielded: fielded };
  }
  var rodMaterial = new THREE.MeshStandardMaterial({ vertexColors: THREE.VertexColors, roughness: 0.55,
                                                     metalness: 0.05, side: THREE.DoubleSide });
  var rods = data.rods.map(function (ids) { return makeTube(ids, layers.rods, rodMaterial, rodColor, true); });
  // Pressure chambers: tubes of their area's circle along their centroid, drawn over the rods
  // (see-through, no depth test) so that they show inside them.
  var chamberColor = new THREE.Color(0x1e9e3c);
  var chamberMaterial = new THREE.MeshStandardMaterial({ vertexColors: THREE.VertexColors, roughness: 0.6,
                                                         transparent: true, opacity: 0.7, depthTest: false,
                                                         depthWrite: false });
  var chambers = (data.chambers || []).map(function (c) {
    var tube = makeTube(c.points, layers.chambers, chamberMaterial, chamberColor, false);
    tube.mesh.renderOrder = 4;
    return tube;
  });

  function updateRod(rod) {
    var ids = rod.ids, n = ids.length, prof = rod.prof, npf = prof.length;
    var geom = rod.mesh.geometry;
    var pos = geom.attributes.position.array, nor = geom.attributes.normal.array, col = geom.attributes.color.array;
    var p = ids.map(point), tang = [];
    // Node tangents for the cubic Hermite centre line: the section's x axis (the rod's tangent
    // for an unsheared rod) times the mean length of the adjacent elements.
    for (var i = 0; i < n; ++i) {
      var a = p[Math.max(i - 1, 0)], b = p[Math.min(i + 1, n - 1)];
      var chord = b.clone().sub(a).multiplyScalar(i > 0 && i < n - 1 ? 0.5 : 1);
      var x = axis(ids[i], 0);
      tang.push(slot[ids[i]] >= 0 && x.dot(chord) > 0 ? x.multiplyScalar(chord.length()) : chord);
    }
    var normal = new THREE.Vector3(), binormal = new THREE.Vector3(), c = new THREE.Color();
    var t = new THREE.Vector3(), v = 0, firstT = null;
    var put = function (k, px, py, pz, nx, ny, nz) {
      pos[3 * k] = px; pos[3 * k + 1] = py; pos[3 * k + 2] = pz;
      nor[3 * k] = nx; nor[3 * k + 1] = ny; nor[3 * k + 2] = nz;
      col[3 * k] = c.r; col[3 * k + 1] = c.g; col[3 * k + 2] = c.b;
    };
    var ends = [];
    for (var e = 0; e + 1 < Math.max(n, 2); ++e) {
      for (var s = e === 0 ? 0 : 1; s <= kSub; ++s) {
        var u = s / kSub, i0 = Math.min(e, n - 1), i1 = Math.min(e + 1, n - 1);
        var h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u;
        var h01 = -2 * u * u * u + 3 * u * u, h11 = u * u * u - u * u;
        var xc = p[i0].clone().multiplyScalar(h00).addScaledVector(tang[i0], h10)
          .addScaledVector(p[i1], h01).addScaledVector(tang[i1], h11);
        var d00 = 6 * u * u - 6 * u, d10 = 3 * u * u - 4 * u + 1, d01 = -d00, d11 = 3 * u * u - 2 * u;
        t.copy(p[i0]).multiplyScalar(d00).addScaledVector(tang[i0], d10)
          .addScaledVector(p[i1], d01).addScaledVector(tang[i1], d11);
        if (t.lengthSq() < 1e-24) t.copy(tang[i0]);
        if (t.lengthSq() < 1e-24) t.set(1, 0, 0);
        t.normalize();
        // Cross-section: the nodes' section y axes interpolated, made normal to the tangent.
        normal.copy(axis(ids[i0], 1)).multiplyScalar(1 - u).addScaledVector(axis(ids[i1], 1), u);
        normal.addScaledVector(t, -normal.dot(t));
        if (normal.lengthSq() < 1e-12) {
          normal.set(Math.abs(t.x) < 0.9 ? 1 : 0, Math.abs(t.x) < 0.9 ? 0 : 1, 0);
          normal.addScaledVector(t, -normal.dot(t));
        }
        normal.normalize();
        binormal.crossVectors(t, normal);
        var hy, hz;
        if (rod.sized) {
          hy = (1 - u) * half[3 * ids[i0] + 1] + u * half[3 * ids[i1] + 1];
          hz = (1 - u) * half[3 * ids[i0] + 2] + u * half[3 * ids[i1] + 2];
        } else {
          hy = hz = thinRadius;
        }
        if (field && rod.fielded) {
          var fv = (1 - u) * curField[fieldSlot[ids[i0]]] + u * curField[fieldSlot[ids[i1]]];
          colormap((fv - field.lo) / (field.hi - field.lo), c);
        } else {
          c.copy(rod.color);
        }
        for (var k = 0; k < npf; ++k, ++v) {
          var q = prof[k];
          put(v, xc.x + hy * q[0] * normal.x + hz * q[1] * binormal.x,
              xc.y + hy * q[0] * normal.y + hz * q[1] * binormal.y,
              xc.z + hy * q[0] * normal.z + hz * q[1] * binormal.z,
              q[2] * normal.x + q[3] * binormal.x, q[2] * normal.y + q[3] * binormal.y,
              q[2] * normal.z + q[3] * binormal.z);
        }
        if (v === npf) firstT = t.clone();
        ends[v === npf ? 0 : 1] = xc;
      }
    }
    // End caps: the first and last rings again with the axial normal, and their centres.
    var rings = rod.rings;
    for (var cap = 0; cap < 2; ++cap) {
      var ring = cap ? rings - 1 : 0, nt_ = cap ? t : firstT, sign = cap ? 1 : -1;
      var base = rings * npf + cap * (npf + 1);
      for (k = 0; k < npf; ++k) {
        var from = ring * npf + k;
        put(base + k, pos[3 * from], pos[3 * from + 1], pos[3 * from + 2], sign * nt_.x, sign * nt_.y, sign * nt_.z);
      }
      var centre = ends[cap] || ends[0];
      put(base + npf, centre.x, centre.y, centre.z, sign * nt_.x, sign * nt_.y, sign * nt_.z);
    }
    geom.attributes.position.needsUpdate = true;
    geom.attributes.normal.needsUpdate = true;
    geom.attributes.color.needsUpdate = true;
  }

  // ---- rigid bodies: contact shapes, else the box of the inertia; links as lines -------------
  var bodyMaterial = new THREE.MeshStandardMaterial({ color: 0x8a94a6, roughness: 0.5, metalness: 0.2 });
  // A box from the inertia is no geometry the run knows: drawn see-through.
  var inertiaMaterial = new THREE.MeshStandardMaterial({ color: 0x8a94a6, roughness: 0.6, transparent: true,
                                                         opacity: 0.35, depthWrite: false });
  var shapes = data.shapes.map(function (s) {
    var parts = [];
    if (s.type === "capsule") {
      parts = [placed(cylinder, bodyMaterial, layers.bodies), placed(sphere, bodyMaterial, layers.bodies),
               placed(sphere, bodyMaterial, layers.bodies)];
    } else if (s.type === "cylinder") {
      parts = [placed(solidCylinder, bodyMaterial, layers.bodies)];
    } else {
      parts = [placed(s.type === "box" ? unitBox : sphere, bodyMaterial, layers.bodies)];
    }
    return { type: s.type, points: s.points, parts: parts };
  });
  function updateShape(s) {
    var c = point(s.points[0]), r = radius[s.points[0]];
    if (s.type === "sphere") {
      s.parts[0].matrix.compose(c, new THREE.Quaternion(), new THREE.Vector3(r, r, r));
    } else if (s.type === "box") {
      s.parts[0].matrix.compose(c, quaternion(s.points[0]), halfSize(s.points[0]).multiplyScalar(2));
    } else if (s.type === "cylinder") {
      between(s.parts[0], c, point(s.points[1]), r);
    } else {
      var b = point(s.points[1]);
      between(s.parts[0], c, b, r);
      s.parts[1].matrix.compose(c, new THREE.Quaternion(), new THREE.Vector3(r, r, r));
      s.parts[2].matrix.compose(b, new THREE.Quaternion(), new THREE.Vector3(r, r, r));
    }
  }
  var bodies = data.bodies.map(function (b) {
    var out = { index: b.index, segments: b.segments, point: b.point, box: null, lump: null,
                shapes: b.shapes };
    if (!b.shapes.length && b.box !== null) {
      var h = halfSize(b.box);
      if (h.x > 0 || h.y > 0 || h.z > 0) out.box = { point: b.box, mesh: placed(unitBox, inertiaMaterial, layers.bodies) };
    }
    if (!b.shapes.length && !out.box && b.point !== null) out.lump = placed(sphere, bodyMaterial, layers.bodies);
    return out;
  });
  // Links: thin grey rods from a body's frame to its joints and centre of mass (a drawing of
  // how the body connects, of no size).
  var linkMaterial = new THREE.MeshStandardMaterial({ color: 0x5b6474, roughness: 0.6 });
  bodies.forEach(function (b) {
    b.links = b.segments.map(function () { return placed(cylinder, linkMaterial, layers.links); });
  });
  function updateBodies() {
    bodies.forEach(function (b) {
      b.segments.forEach(function (seg, k) { between(b.links[k], point(seg[0]), point(seg[1]), 0.5 * thinRadius); });
      if (b.box) {
        var h = halfSize(b.box.point).multiplyScalar(2);
        h.set(Math.max(h.x, 1e-3 * size0), Math.max(h.y, 1e-3 * size0), Math.max(h.z, 1e-3 * size0));
        b.box.mesh.matrix.compose(point(b.box.point), quaternion(b.box.point), h);
      }
      if (b.lump) b.lump.matrix.compose(point(b.point), new THREE.Quaternion(), new THREE.Vector3(1, 1, 1).multiplyScalar(jointRadius));
    });
    shapes.forEach(updateShape);
  }

  // ---- obstacles (fixed): planes as a patch around the motion, spheres, capsules -------------
  var obstacleMaterial = new THREE.MeshStandardMaterial({ color: 0xb9ae98, roughness: 0.8 });
  var planeMaterial = new THREE.MeshBasicMaterial({ color: 0xcfc6b4, transparent: true, opacity: 0.35,
                                                    side: THREE.DoubleSide, depthWrite: false });
  data.obstacles.forEach(function (o) {
    var c = point(o.points[0]), r = radius[o.points[0]];
    if (o.type === "plane") {
      var q = quaternion(o.points[0]), n = axis(o.points[0], 2);
      // Centred where the motion's centre projects onto the plane, 1.5 times its size.
      var mid = box.getCenter(new THREE.Vector3());
      mid.addScaledVector(n, -mid.clone().sub(c).dot(n));
      var m = new THREE.Mesh(new THREE.PlaneBufferGeometry(1.5 * size, 1.5 * size), planeMaterial);
      m.position.copy(mid);
      m.quaternion.copy(q);  // the patch's normal (local z) along the plane's
      m.renderOrder = -1;
      layers.obstacles.add(m);
    } else if (o.type === "sphere") {
      placed(sphere, obstacleMaterial, layers.obstacles).matrix.compose(c, new THREE.Quaternion(), new THREE.Vector3(r, r, r));
    } else if (o.type === "box") {
      placed(unitBox, obstacleMaterial, layers.obstacles).matrix.compose(c, quaternion(o.points[0]),
                                                                        halfSize(o.points[0]).multiplyScalar(2));
    } else if (o.type === "cylinder") {
      between(placed(solidCylinder, obstacleMaterial, layers.obstacles), c, point(o.points[1]), r);
    } else {
      var b = point(o.points[1]);
      between(placed(cylinder, obstacleMaterial, layers.obstacles), c, b, r);
      placed(sphere, obstacleMaterial, layers.obstacles).matrix.compose(c, new THREE.Quaternion(), new THREE.Vector3(r, r, r));
      placed(sphere, obstacleMaterial, layers.obstacles).matrix.compose(b, new THREE.Quaternion(), new THREE.Vector3(r, r, r));
    }
  });

  // ---- tendons and force elements: thin tubes coloured by tension -----------------------------
  var maxTension = 0;
  for (i = 0; i < nl * nf; ++i) maxTension = Math.max(maxTension, Math.abs(tensionTrack[i]));
  var lines = data.lines.map(function (l, k) {
    var mat = new THREE.MeshBasicMaterial({ color: 0x000000 });
    var segs = [];
    for (var s = 0; s + 1 < l.points.length; ++s) segs.push(placed(cylinder, mat, layers.tendons));
    var joints_ = l.points.map(function () { return placed(sphere, mat, layers.tendons); });
    var label = l.name ? textSprite(l.name, "#1d2430", 0.03 * size0) : null;
    if (label) layers.labels.add(label);
    return { k: k, points: l.points, kind: l.kind, material: mat, segs: segs, knots: joints_, label: label };
  });
  function updateLines() {
    var c = new THREE.Color();
    lines.forEach(function (l) {
      var T = curTension[l.k];
      colormap(maxTension > 0 ? Math.max(T, 0) / maxTension : 0, c);
      l.material.color.copy(c);
      var r = l.kind === "tendon" ? lineRadius : 0.7 * lineRadius;
      var p = l.points.map(point);
      l.segs.forEach(function (m, s) { between(m, p[s], p[s + 1], r); });
      l.knots.forEach(function (m, s) { m.matrix.compose(p[s], new THREE.Quaternion(), new THREE.Vector3(r, r, r)); });
      if (l.label) l.label.position.copy(p[0].clone().add(p[p.length - 1]).multiplyScalar(0.5)).addScaledVector(up, 2 * jointRadius);
    });
  }

  // ---- contact forces: arrows from the contact point along the force on the shape ----------------
  var maxForce = 0;
  for (i = 0; i + 2 < forceTrack.length; i += 3)
    maxForce = Math.max(maxForce, Math.hypot(forceTrack[i], forceTrack[i + 1], forceTrack[i + 2]));
  var forceScale = Number(params.get("force_scale")), forceScaleFixed = forceScale > 0;
  if (!(forceScale > 0)) forceScale = maxForce > 0 ? 0.15 * size0 / maxForce : 0;
  var arrowRadius = 0.004 * size0;
  var arrowMaterial = new THREE.MeshBasicMaterial({ color: 0xe31a1c, depthTest: false, transparent: true });
  // A slipping contact's arrow is orange (sticking, and without state data: red).
  var slipMaterial = new THREE.MeshBasicMaterial({ color: 0xff9f1c, depthTest: false, transparent: true });
  function hasStates() { return nc > 0 && stateTrack.length >= 3 * nc * nf; }
  // "contacts: 3 stick, 1 slip; share <= 0.62; deflection <= 8.4 um" at the current time.
  function contactSummary() {
    if (!hasStates()) return "";
    var stick = 0, slip = 0, share = 0, defl = 0;
    for (var k = 0; k < nc; ++k) {
      if (!(Math.hypot(curForce[3 * k], curForce[3 * k + 1], curForce[3 * k + 2]) > 1e-9 * maxForce)) continue;
      if (curState[3 * k] > 0.5) ++slip; else ++stick;
      defl = Math.max(defl, curState[3 * k + 1]);
      share = Math.max(share, curState[3 * k + 2]);
    }
    if (stick + slip === 0) return "";
    return "  \u00b7  contacts: " + stick + " stick, " + slip + " slip; friction share \u2264 " +
      share.toFixed(2) + "; deflection \u2264 " + (defl * 1e6).toPrecision(3) + " \u00b5m";
  }
  var arrows = data.contacts.map(function (p) {
    var shaft = placed(cylinder, arrowMaterial, layers.forces), head = placed(cone, arrowMaterial, layers.forces);
    shaft.renderOrder = head.renderOrder = 5;
    return { point: p, shaft: shaft, head: head };
  });
  function updateArrows() {
    arrows.forEach(function (a, k) {
      var F = new THREE.Vector3(curForce[3 * k], curForce[3 * k + 1], curForce[3 * k + 2]);
      var len = F.length() * forceScale;
      var on = len > 1e-6 * size0 && F.length() > 1e-9 * maxForce;
      a.shaft.visible = a.head.visible = on;
      if (!on) return;
      var mat = hasStates() && curState[3 * k] > 0.5 ? slipMaterial : arrowMaterial;
      a.shaft.material = a.head.material = mat;
      var dir = F.normalize(), from = point(a.point);
      var headLen = Math.min(4 * arrowRadius, 0.5 * len);
      var neck = from.clone().addScaledVector(dir, len - headLen);
      between(a.shaft, from, neck, arrowRadius);
      between(a.head, neck, from.clone().addScaledVector(dir, len), 2.2 * arrowRadius);
    });
  }

  // ---- joints: spheres (actuated orange, passive teal, welds grey) and frames -----------------
  var jointMaterials = {
    actuated: new THREE.MeshStandardMaterial({ color: 0xe07b24, roughness: 0.4 }),
    passive: new THREE.MeshStandardMaterial({ color: 0x17a589, roughness: 0.4 }),
    weld: new THREE.MeshStandardMaterial({ color: 0x59606b, roughness: 0.6 }),
  };
  // Joints at the same place (a hinge and a weld at one point) share one label, "J1, W1".
  function point0(i) { return new THREE.Vector3(x0[3 * i], x0[3 * i + 1], x0[3 * i + 2]); }
  var labelOwner = data.joints.map(function (j, k) {
    for (var i = 0; i < k; ++i)
      if (point0(data.joints[i].point).distanceTo(point0(j.point)) < 1e-6 * size) return i;
    return k;
  });
  var joints = data.joints.map(function (j, k) {
    var kind = j.type === "fixed" ? "weld" : j.drive && j.drive !== "none" ? "actuated" : "passive";
    var m = new THREE.Mesh(sphere, jointMaterials[kind]);
    var r = kind === "weld" ? 0.6 * jointRadius : jointRadius;
    m.scale.set(r, r, r);
    layers.joints.add(m);
    var label = null;
    if (j.name && labelOwner[k] === k) {
      var names = data.joints.filter(function (o, i) { return labelOwner[i] === k && o.name; })
        .map(function (o) { return o.name; });
      label = textSprite(names.join(", "), "#1d2430", 0.03 * size0);
      layers.labels.add(label);
    }
    return { point: j.point, mesh: m, label: label, name: j.name };
  });
  var frameGeometry = new THREE.BufferGeometry();
  frameGeometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(18 * joints.length), 3));
  var frameColors = new Float32Array(18 * joints.length);
  for (i = 0; i < joints.length; ++i)
    for (var a = 0; a < 3; ++a)
      for (var e = 0; e < 2; ++e) frameColors[18 * i + 6 * a + 3 * e + a] = a === 1 ? 0.6 : 0.85;
  frameGeometry.setAttribute("color", new THREE.BufferAttribute(frameColors, 3));
  var frames = new THREE.LineSegments(frameGeometry, new THREE.LineBasicMaterial({ vertexColors: THREE.VertexColors }));
  frames.frustumCulled = false;
  layers.frames.add(frames);
  function updateJoints() {
    var fp = frameGeometry.attributes.position.array, len = 3.5 * jointRadius;
    joints.forEach(function (j, k) {
      var x = point(j.point);
      j.mesh.position.copy(x);
      if (j.label) j.label.position.copy(x).addScaledVector(up, 2.2 * jointRadius);
      for (var a = 0; a < 3; ++a) {
        var tip = x.clone().addScaledVector(axis(j.point, a), len), o = 18 * k + 6 * a;
        fp[o] = x.x; fp[o + 1] = x.y; fp[o + 2] = x.z; fp[o + 3] = tip.x; fp[o + 4] = tip.y; fp[o + 5] = tip.z;
      }
    });
    frameGeometry.attributes.position.needsUpdate = true;
  }

  // ---- recorded points and their trails -------------------------------------------------------
  var recPoints = [];
  if (rec) {
    var recColors = [0xc2185b, 0x6a1b9a, 0xad1457, 0x4527a0, 0x880e4f];  // magentas and purples
    var nr = recTimes.length, npr = rec.names.length;
    rec.names.forEach(function (name, k) {
      var color = recColors[k % recColors.length];
      var m = new THREE.Mesh(sphere, new THREE.MeshStandardMaterial({ color: color, roughness: 0.4 }));
      var r = 0.6 * jointRadius;
      m.scale.set(r, r, r);
      layers.points.add(m);
      var trailPos = new Float32Array(nr * 3);
      for (var i = 0; i < nr; ++i)
        for (var c = 0; c < 3; ++c) trailPos[3 * i + c] = recXyz[3 * (i * npr + k) + c];
      var g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(trailPos, 3));
      var line = new THREE.Line(g, new THREE.LineBasicMaterial({ color: color, transparent: true, opacity: 0.75 }));
      line.frustumCulled = false;
      layers.points.add(line);
      var label = textSprite(name, "#" + new THREE.Color(color).getHexString(), 0.03 * size0);
      layers.labels.add(label);
      recPoints.push({ name: name, k: k, mesh: m, line: line, label: label });
    });
  }
  function recordedPoint(k, t) {
    var kw = bracket(recTimes, t), i = kw[0], w = kw[1], npr = rec.names.length;
    var a = 3 * (i * npr + k), out = new THREE.Vector3(recXyz[a], recXyz[a + 1], recXyz[a + 2]);
    if (w > 0) {
      var b = 3 * ((i + 1) * npr + k);
      out.lerp(new THREE.Vector3(recXyz[b], recXyz[b + 1], recXyz[b + 2]), w);
    }
    return out;
  }

  // ---- follow targets ---------------------------------------------------------------------
  var targets = [];
  recPoints.forEach(function (p) { targets.push({ name: p.name, what: "point", center: function (t) { return recordedPoint(p.k, t); } }); });
  joints.forEach(function (j) {
    if (j.name) targets.push({ name: j.name, what: "joint", center: function () { return point(j.point); } });
  });
  function centroid(list) {
    var c = new THREE.Vector3();
    list.forEach(function (i) { c.add(point(i)); });
    return c.multiplyScalar(1 / Math.max(list.length, 1));
  }
  data.bodies.forEach(function (b, k) {
    var ids = [];
    b.segments.forEach(function (s) { ids.push(s[0], s[1]); });
    if (b.point !== null) ids.push(b.point);
    if (b.box !== null) ids.push(b.box);
    b.shapes.forEach(function (s) { ids.push(data.shapes[s].points[0]); });
    if (ids.length) targets.push({ name: b.name || "rigid body " + (k + 1), what: "body", center: function () { return centroid(ids); } });
  });
  data.rods.forEach(function (ids, k) {
    targets.push({ name: (data.rod_names && data.rod_names[k]) || "rod " + (k + 1), what: "rod", center: function () { return centroid(ids); } });
  });
  var followSelect = document.getElementById("follow");
  targets.forEach(function (tg, k) {
    var o = document.createElement("option");
    o.value = String(k);
    o.textContent = tg.what + " " + tg.name;
    followSelect.appendChild(o);
  });
  var follow = null, followLast = null;
  function setFollow(k) {
    follow = k === "" || k === null ? null : targets[Number(k)];
    followLast = null;
  }

  // ---- state and drawing -------------------------------------------------------------------
  var time = t0, playing = false, speed = 1, trail = 1;

  function update() {
    computeState(time);
    rods.forEach(updateRod);
    chambers.forEach(updateRod);
    updateBodies();
    updateLines();
    updateArrows();
    updateJoints();
    recPoints.forEach(function (p) {
      var x = recordedPoint(p.k, time);
      p.mesh.position.copy(x);
      p.label.position.copy(x).addScaledVector(up, -2.4 * jointRadius);  // joints' labels go above
      var end = bracket(recTimes, time)[0] + 1;
      var start = trail === "all" ? 0 : bracket(recTimes, time - trail)[0];
      p.line.geometry.setDrawRange(start, trail === 0 ? 0 : end - start);
    });
    if (follow) {
      var c = follow.center(time);
      if (followLast) {
        var d = c.clone().sub(followLast);
        camera.position.add(d);
        controls.target.add(d);
      } else {
        // Start following: look at the target from the current direction, from a distance
        // that shows the mechanism (its initial size), whatever distance the motion needs.
        var dir = camera.position.clone().sub(controls.target).normalize();
        var dist = 0.6 * size0 / Math.tan(35 * Math.PI / 360);
        controls.target.copy(c);
        camera.position.copy(c).addScaledVector(dir, dist);
      }
      followLast = c;
      controls.update();
    }
    document.getElementById("time").textContent = data.static
      ? "\u03bb = " + time.toFixed(3) + "  (load factor, " + t0.toFixed(3) + " to " + t1.toFixed(3) + ")"
      : "t = " + time.toFixed(3) + " s  (" + t0.toFixed(3) + " to " + t1.toFixed(3) + " s)";
    document.getElementById("time").textContent += contactSummary();
    var slider = document.getElementById("slider");
    if (document.activeElement !== slider || playing)
      slider.value = String(Math.round(1000 * (t1 > t0 ? (time - t0) / (t1 - t0) : 0)));
  }

  function resize() {
    var w = container.clientWidth || window.innerWidth, h = container.clientHeight || window.innerHeight;
    renderer.setSize(w, h, false);
    renderer.domElement.style.width = w + "px";
    renderer.domElement.style.height = h + "px";
    aspect = w / Math.max(h, 1);
    setProjection(ortho ? orthoWidth : 0);
  }

  function render() {
    layerNames.forEach(function (n) { layers[n].visible = shown[n]; });
    renderer.render(scene, camera);
    // Screen box of the mechanism's points (the test compares it with the pixels).
    var w = renderer.domElement.clientWidth, h = renderer.domElement.clientHeight;
    var sx0 = Infinity, sy0 = Infinity, sx1 = -Infinity, sy1 = -Infinity, v = new THREE.Vector3();
    for (var i = 0; i < np; ++i) {
      if (isObstacle[i]) continue;
      v.set(cur[3 * i], cur[3 * i + 1], cur[3 * i + 2]).project(camera);
      var sx = (v.x + 1) / 2 * w, sy = (1 - v.y) / 2 * h;
      sx0 = Math.min(sx0, sx); sx1 = Math.max(sx1, sx); sy0 = Math.min(sy0, sy); sy1 = Math.max(sy1, sy);
    }
    document.body.setAttribute("data-time", time.toFixed(6));
    document.body.setAttribute("data-bbox", [sx0, sy0, sx1, sy1].map(Math.round).join(","));
  }
  // Screen position [CSS px] of a world point (for tests and links).
  window.screwfemProject = function (x, y, z) {
    var v = new THREE.Vector3(x, y, z).project(camera);
    return [(v.x + 1) / 2 * renderer.domElement.clientWidth, (1 - v.y) / 2 * renderer.domElement.clientHeight];
  };

  // ---- controls --------------------------------------------------------------------------
  var playButton = document.getElementById("play");
  var scheduled = false, last = null;
  // Frames are requested only while playing: a paused page does no work and is idle, as a
  // headless browser taking a screenshot expects.
  function schedule() {
    if (!scheduled && playing) { scheduled = true; requestAnimationFrame(tick); }
  }
  function setPlaying(on) {
    playing = on && t1 > t0;
    playButton.textContent = playing ? "Pause" : "Play";
    last = null;
    schedule();
  }
  function tick(now) {
    scheduled = false;
    if (!playing) return;
    if (last !== null) {
      time += speed * (now - last) / 1000;
      if (time > t1) {
        if (document.getElementById("loop").checked) time = t0 + (time - t1) % Math.max(t1 - t0, 1e-9);
        else { time = t1; setPlaying(false); }
      }
    }
    last = now;
    update();
    render();
    schedule();
  }
  playButton.addEventListener("click", function () {
    if (!playing && time >= t1) time = t0;
    setPlaying(!playing);
  });
  document.getElementById("slider").addEventListener("input", function (e) {
    time = t0 + (t1 - t0) * Number(e.target.value) / 1000;
    liveFollow = Number(e.target.value) >= 1000;  // a live page follows the simulation at the end
    update();
    render();
  });
  var speedSelect = document.getElementById("speed");
  speedSelect.addEventListener("change", function (e) { speed = Number(e.target.value); });
  document.getElementById("trail").addEventListener("change", function (e) {
    trail = e.target.value === "all" ? "all" : Number(e.target.value);
    update(); render();
  });
  followSelect.addEventListener("change", function (e) { setFollow(e.target.value); update(); render(); });
  var layerBox = document.getElementById("layers");
  layerNames.forEach(function (n) {
    var label = document.createElement("label"), box_ = document.createElement("input");
    box_.type = "checkbox";
    box_.id = "show-" + n;
    box_.checked = shown[n];
    box_.addEventListener("change", function () { shown[n] = box_.checked; render(); });
    label.appendChild(box_);
    label.appendChild(document.createTextNode(n));
    layerBox.appendChild(label);
  });
  document.getElementById("reset").addEventListener("click", function () {
    followSelect.value = ""; setFollow(null); frameAll(false); update(); render();
  });
  var colourSelect = document.getElementById("colour");
  fields.forEach(function (f, k) {
    var o = document.createElement("option");
    o.value = String(k);
    o.textContent = f.name + (f.unit ? " [" + f.unit + "]" : "");
    colourSelect.appendChild(o);
  });
  function setField(k) {
    field = k === "" || k === null ? null : fields[Number(k)];
    var legend = document.getElementById("legend-field");
    legend.hidden = !field;
    if (field) {
      document.getElementById("legend-name").textContent = field.name + (field.unit ? " [" + field.unit + "]" : "");
      document.getElementById("legend-min").textContent = field.lo.toPrecision(3);
      document.getElementById("legend-max").textContent = field.hi.toPrecision(3);
    }
  }
  colourSelect.addEventListener("change", function (e) { setField(e.target.value); update(); render(); });
  window.addEventListener("keydown", function (e) {
    if (e.target.tagName === "SELECT" || e.target.tagName === "INPUT" && e.target.type !== "range") return;
    if (e.key === " ") { e.preventDefault(); playButton.click(); }
    var step = nf > 1 ? (t1 - t0) / (nf - 1) : 0;
    if (e.key === "ArrowRight" || e.key === "ArrowLeft") {
      e.preventDefault();
      setPlaying(false);
      time = Math.min(Math.max(time + (e.key === "ArrowRight" ? step : -step), t0), t1);
      update(); render();
    }
  });
  controls.addEventListener("change", function () { if (!playing) render(); });
  window.addEventListener("resize", function () { resize(); render(); });


  // ---- live view (Simulation.view): frames over a WebSocket -----------------------------------
  // data.live: the page was served by a running simulation (python/screwfem/_live.py). Every
  // message is a frame ({t, x, q, tension, forces, fields}: the moving points' positions, the
  // turning points' quaternions, ... as base64 float32, in the order of the data's tracks) or
  // the simulation's state ({paused}). The page shows the newest frame while the slider is at
  // its end (liveFollow); the Pause button pauses the simulation itself.
  var liveFollow = true;
  var LIVE_MAX_FRAMES = 20000;  // beyond, the oldest half is dropped
  function grow(arr, need) {
    if (arr.length >= need) return arr;
    var out = new Float32Array(Math.max(need, 2 * arr.length, 64));
    out.set(arr);
    return out;
  }
  function dropOldest(k) {
    times.splice(0, k);
    var shift = function (arr, stride) { arr.copyWithin(0, k * stride, nf * stride); };
    shift(track, 3 * nm); shift(quats, 4 * nt); shift(tensionTrack, nl); shift(forceTrack, 3 * nc);
    fields.forEach(function (f) { shift(f.values, fieldPoints.length); });
    nf -= k;
    t0 = times[0];
  }
  function appendFrame(m) {
    if (nf >= LIVE_MAX_FRAMES) dropOldest(nf >> 1);
    var x = floats(m.x), q = floats(m.q), fc = floats(m.forces), i;
    track = grow(track, (nf + 1) * 3 * nm); track.set(x.subarray(0, 3 * nm), nf * 3 * nm);
    quats = grow(quats, (nf + 1) * 4 * nt); quats.set(q.subarray(0, 4 * nt), nf * 4 * nt);
    tensionTrack = grow(tensionTrack, (nf + 1) * nl);
    for (i = 0; i < nl; ++i) {
      tensionTrack[nf * nl + i] = m.tension[i];
      maxTension = Math.max(maxTension, Math.abs(m.tension[i]));
    }
    if (nc) {
      forceTrack = grow(forceTrack, (nf + 1) * 3 * nc); forceTrack.set(fc.subarray(0, 3 * nc), nf * 3 * nc);
      for (i = 0; i + 2 < fc.length; i += 3) maxForce = Math.max(maxForce, Math.hypot(fc[i], fc[i + 1], fc[i + 2]));
      if (!forceScaleFixed && maxForce > 0) forceScale = 0.15 * size0 / maxForce;
    }
    fields.forEach(function (f, k) {
      var v = floats(m.fields[k]), n = fieldPoints.length;
      f.values = grow(f.values, (nf + 1) * n); f.values.set(v.subarray(0, n), nf * n);
      for (i = 0; i < n; ++i) { if (v[i] < f.lo) f.lo = v[i]; if (v[i] > f.hi) f.hi = v[i]; }
    });
    times.push(m.t);
    nf += 1;
    t1 = m.t;
    if (nf === 1) t0 = m.t;
    if (liveFollow) time = t1;
    // Until the camera is moved by hand, the picture frames the whole motion so far.
    var before = box.clone();
    for (i = 0; i < nm; ++i) {
      var p = moving[i];
      if (!isObstacle[p]) expand(box, x[3 * i], x[3 * i + 1], x[3 * i + 2], radius[p] || 0);
    }
    if (liveFrame && !box.equals(before)) {
      size = Math.max(box.getSize(new THREE.Vector3()).length(), 1e-6);
      frameAll(true);
    }
  }
  var liveFrame = true;
  controls.addEventListener("start", function () { liveFrame = false; });
  var liveDrawPending = false;
  function liveDraw() {
    if (liveDrawPending) return;
    liveDrawPending = true;
    requestAnimationFrame(function () {
      liveDrawPending = false;
      update();
      render();
    });
  }
  function startLive() {
    var body = document.body, received = 0, paused = false;
    var pause = document.getElementById("live-pause");
    pause.hidden = false;
    body.setAttribute("data-live", "connecting");
    body.setAttribute("data-received", "0");
    body.setAttribute("data-frames", String(nf));
    var socket = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + data.live.path);
    window.screwfemLive = socket;
    socket.onopen = function () { body.setAttribute("data-live", "open"); };
    socket.onclose = function () {
      body.setAttribute("data-live", "closed");
      pause.disabled = true;
      pause.textContent = "ended";
    };
    socket.onmessage = function (e) {
      var m = JSON.parse(e.data);
      if ("paused" in m) {
        paused = m.paused;
        pause.textContent = paused ? "Resume sim" : "Pause sim";
        body.setAttribute("data-paused", paused ? "1" : "0");
        return;
      }
      appendFrame(m);
      received += 1;
      body.setAttribute("data-received", String(received));
      body.setAttribute("data-frames", String(nf));
      body.setAttribute("data-sim-time", String(m.t));
      liveDraw();
    };
    pause.addEventListener("click", function () {
      if (socket.readyState === 1) socket.send(JSON.stringify({ pause: !paused }));
    });
  }

  // ---- start -------------------------------------------------------------------------------
  document.getElementById("case").textContent = data.name || "screwfem run";
  var notes = [];
  if (data.live) notes.push("live: following the running simulation");
  else if (data.status && data.status !== "completed") notes.push("run " + data.status + (data.message ? ": " + data.message : ""));
  notes = notes.concat(data.notes || []);
  document.getElementById("note").textContent = notes.join(" \u00b7 ");
  // Legends of the tension colours and the arrows' scale.
  if (lines.length) {
    document.getElementById("legend-tension").hidden = false;
    document.getElementById("tension-max").textContent = maxTension.toPrecision(3) + " N";
  }
  if (forceScale > 0 && arrows.length) {
    var ref = Math.pow(10, Math.floor(Math.log10(0.1 * size0)));  // a round length
    document.getElementById("legend-force").hidden = false;
    document.getElementById("force-scale").textContent =
      (ref >= 0.01 ? (ref * 100).toPrecision(2) + " cm" : (ref * 1000).toPrecision(2) + " mm") +
      " = " + (ref / forceScale).toPrecision(3) + " N";
  }
  if (params.has("speed") && Number(params.get("speed")) > 0) {
    speed = Number(params.get("speed"));
    var so = Array.prototype.find.call(speedSelect.options, function (o) { return Number(o.value) === speed; });
    if (!so) { so = document.createElement("option"); so.value = String(speed); so.textContent = speed + "x"; speedSelect.appendChild(so); }
    speedSelect.value = so.value;
  }
  resize();
  frameAll(true);
  if (params.has("colour")) {
    fields.forEach(function (f, k) { if (f.name === params.get("colour")) { colourSelect.value = String(k); setField(k); } });
  }
  if (params.has("follow")) {
    targets.forEach(function (tg, k) { if (tg.name === params.get("follow")) { followSelect.value = String(k); setFollow(k); } });
  }
  if (params.has("trail")) {
    var tr = params.get("trail"), trailSelect = document.getElementById("trail");
    trail = tr === "all" ? "all" : Math.max(Number(tr) || 0, 0);
    if (!Array.prototype.some.call(trailSelect.options, function (o) { return o.value === tr; })) {
      var o = document.createElement("option");
      o.value = tr;
      o.textContent = tr + " s";
      trailSelect.appendChild(o);
    }
    trailSelect.value = tr;
  }
  var frozen = params.has("t");
  if (frozen) {
    var tq = Number(params.get("t"));
    time = isFinite(tq) ? Math.min(Math.max(tq, t0), t1) : t0;
  }
  update();
  render();
  if (unsized && !data.notes.some(function (n) { return n.indexOf("no section size") >= 0; }))
    document.getElementById("note").textContent += " \u00b7 rods without a section size: drawn thin";
  if (document.body.getAttribute("data-state") !== "error") document.body.setAttribute("data-state", "ready");
  if (data.live) startLive();
  else if (!frozen) setPlaying(nf > 1);
})();
