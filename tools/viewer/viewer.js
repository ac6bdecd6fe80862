// The screwfem viewer (inlined into the page by tools/screwfem_view.py; three.js r111).
//
// The run's data (element #run-data, written by screwfem_view.py) holds the drawn geometry of
// every ParaView frame: point positions and frames, rods as point lists, rigid bodies as
// segments, joints as points, per-point scalar fields to colour the rods by, and the recorded
// points (points.csv). Between frames, positions are interpolated linearly in time.
//
// URL parameters (for tests and links): t=SECONDS shows that time and stays paused;
// bare=1 draws the mechanism alone (no grid, axes, trails, labels or controls);
// follow=NAME follows a body, rod, joint or recorded point; colour=FIELD colours the rods;
// labels=1 shows the names of joints and recorded points; trail=SECONDS or all.
(function () {
  "use strict";

  var data = JSON.parse(document.getElementById("run-data").textContent);
  var params = new URLSearchParams(window.location.search);
  var bare = params.get("bare") === "1";
  if (bare) document.body.classList.add("bare");

  // ---- data --------------------------------------------------------------------------------
  function floats(b64) {
    var bytes = atob(b64), n = bytes.length, buf = new Uint8Array(n);
    for (var i = 0; i < n; ++i) buf[i] = bytes.charCodeAt(i);
    return new Float32Array(buf.buffer);
  }
  var times = data.times, nf = times.length, np = data.npoints;
  var positions = floats(data.positions);
  var axes = data.axes ? floats(data.axes) : null;
  var fields = data.fields.map(function (f) {
    var v = floats(f.values), lo = Infinity, hi = -Infinity;
    for (var i = 0; i < v.length; ++i) { if (v[i] < lo) lo = v[i]; if (v[i] > hi) hi = v[i]; }
    return { name: f.name, unit: f.unit, values: v, lo: lo, hi: hi > lo ? hi : lo + 1 };
  });
  var rec = data.recorded;
  var recXyz = rec ? floats(rec.xyz) : null, recTimes = rec ? rec.times : [];
  var t0 = nf ? times[0] : 0, t1 = nf ? times[nf - 1] : 0;

  // Current geometry: interpolated positions (np x 3), frame axes (np x 9), field (np).
  var cur = new Float32Array(np * 3), curAxes = new Float32Array(np * 9), curField = new Float32Array(np);
  var field = null;

  // Index k and weight w with t between times[k] and times[k+1] (w in [0, 1]).
  function bracket(ts, t) {
    if (ts.length < 2 || t <= ts[0]) return [0, 0];
    if (t >= ts[ts.length - 1]) return [ts.length - 1, 0];
    var lo = 0, hi = ts.length - 1;
    while (hi - lo > 1) { var mid = (lo + hi) >> 1; if (ts[mid] <= t) lo = mid; else hi = mid; }
    return [lo, (t - ts[lo]) / (ts[lo + 1] - ts[lo])];
  }
  function lerpInto(out, src, stride, k, w) {
    var a = k * stride, b = (k + 1) * stride;
    for (var i = 0; i < stride; ++i) out[i] = w > 0 ? src[a + i] + w * (src[b + i] - src[a + i]) : src[a + i];
  }
  function computeState(t) {
    var kw = bracket(times, t);
    lerpInto(cur, positions, np * 3, kw[0], kw[1]);
    if (axes) lerpInto(curAxes, axes, np * 9, kw[0], kw[1]);
    if (field) lerpInto(curField, field.values, np, kw[0], kw[1]);
  }
  function point(i) { return new THREE.Vector3(cur[3 * i], cur[3 * i + 1], cur[3 * i + 2]); }
  function axis(i, a) {
    var o = 9 * i + 3 * a;
    return new THREE.Vector3(curAxes[o], curAxes[o + 1], curAxes[o + 2]);
  }

  // Bounding box of the whole motion (all frames and recorded points): sizes and framing.
  var box = new THREE.Box3();
  for (var i = 0; i + 2 < positions.length; i += 3)
    box.expandByPoint(new THREE.Vector3(positions[i], positions[i + 1], positions[i + 2]));
  if (recXyz)
    for (i = 0; i + 2 < recXyz.length; i += 3)
      box.expandByPoint(new THREE.Vector3(recXyz[i], recXyz[i + 1], recXyz[i + 2]));
  if (box.isEmpty()) box.set(new THREE.Vector3(-0.5, -0.5, -0.5), new THREE.Vector3(0.5, 0.5, 0.5));
  var size = Math.max(box.getSize(new THREE.Vector3()).length(), 1e-6);
  // The mechanism's own size (its initial bounding box) sets the drawn thicknesses and the
  // following camera's distance; the motion's size (box) sets the grid and the overall view.
  var box0 = new THREE.Box3();
  for (i = 0; i + 2 < np * 3; i += 3)
    box0.expandByPoint(new THREE.Vector3(positions[i], positions[i + 1], positions[i + 2]));
  if (recXyz)
    for (i = 0; i + 2 < 3 * rec.names.length; i += 3)
      box0.expandByPoint(new THREE.Vector3(recXyz[i], recXyz[i + 1], recXyz[i + 2]));
  var size0 = box0.isEmpty() ? size : Math.max(box0.getSize(new THREE.Vector3()).length(), 1e-3 * size);
  var tubeRadius = 0.006 * size0, bodyWidth = 0.016 * size0, jointRadius = 0.014 * size0;
  var up = new THREE.Vector3().fromArray(data.up).normalize();

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
  var camera = new THREE.PerspectiveCamera(35, 1, size * 1e-3, size * 100);
  camera.up.copy(up);
  var controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.enableDamping = false;
  controls.screenSpacePanning = true;

  scene.add(new THREE.HemisphereLight(0xffffff, 0x8890a0, 0.75));
  var sun = new THREE.DirectionalLight(0xffffff, 0.65);
  sun.position.set(1, -1, 2);
  camera.add(sun);
  scene.add(camera);

  // Views the whole motion from the front-right and above (the up axis points up), from the
  // nearest distance at which every corner of the motion's bounding box is in the picture.
  function frameAll() {
    var center = box.getCenter(new THREE.Vector3());
    var side = new THREE.Vector3(1, 0, 0);
    if (Math.abs(side.dot(up)) > 0.9) side.set(0, 1, 0);
    side.sub(up.clone().multiplyScalar(side.dot(up))).normalize();
    var depth = new THREE.Vector3().crossVectors(up, side);  // side x depth = up
    var dir = side.clone().multiplyScalar(0.55).add(depth.multiplyScalar(-0.8))
      .add(up.clone().multiplyScalar(0.5)).normalize();
    var right = new THREE.Vector3().crossVectors(dir, up).negate().normalize();
    var camUp = new THREE.Vector3().crossVectors(right, dir).negate().normalize();
    var tanV = Math.tan(camera.fov * Math.PI / 360), tanH = tanV * camera.aspect;
    var dist = 0;
    for (var c = 0; c < 8; ++c) {
      var corner = new THREE.Vector3(c & 1 ? box.max.x : box.min.x, c & 2 ? box.max.y : box.min.y,
                                     c & 4 ? box.max.z : box.min.z).sub(center);
      var along = corner.dot(dir);  // towards the camera
      dist = Math.max(dist, along + Math.abs(corner.dot(right)) / tanH,
                      along + Math.abs(corner.dot(camUp)) / tanV);
    }
    dist = Math.max(dist * 1.08, 1e-3 * size);
    controls.target.copy(center);
    camera.position.copy(center).add(dir.multiplyScalar(dist));
    camera.near = dist * 1e-3;
    camera.far = dist * 50;
    camera.updateProjectionMatrix();
    controls.update();
  }

  // ---- ground grid and axes -----------------------------------------------------------------
  var decor = new THREE.Group();
  scene.add(decor);
  (function () {
    var lo = box.min.dot(up), hi = box.max.dot(up);
    var floor = Math.min(0, lo);
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
    decor.add(grid);
    var axesLen = Math.max(step, 0.12 * size);
    var ax = new THREE.AxesHelper(axesLen);
    decor.add(ax);
    ["x", "y", "z"].forEach(function (name, k) {
      var s = textSprite(name, ["#d0342c", "#2a9d3c", "#2c5fd0"][k], 0.035 * size);
      s.position.setComponent(k, axesLen * 1.08);
      decor.add(s);
    });
    void hi;
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

  // ---- rods: tubes through the node frames -------------------------------------------------
  var kSub = 6, kRadial = 12;
  var rodColor = new THREE.Color(0x2f7fc1);
  var rods = data.rods.map(function (ids) {
    var rings = (ids.length - 1) * kSub + 1, nv = rings * (kRadial + 1);
    var geom = new THREE.BufferGeometry();
    var pos = new Float32Array(nv * 3), nor = new Float32Array(nv * 3), col = new Float32Array(nv * 3);
    geom.setAttribute("position", new THREE.BufferAttribute(pos, 3));
    geom.setAttribute("normal", new THREE.BufferAttribute(nor, 3));
    geom.setAttribute("color", new THREE.BufferAttribute(col, 3));
    var index = [];
    for (var r = 0; r + 1 < rings; ++r)
      for (var s = 0; s < kRadial; ++s) {
        var a = r * (kRadial + 1) + s, b = a + kRadial + 1;
        index.push(a, b, a + 1, b, b + 1, a + 1);
      }
    geom.setIndex(index);
    var mat = new THREE.MeshStandardMaterial({ vertexColors: THREE.VertexColors, roughness: 0.55, metalness: 0.05 });
    var mesh = new THREE.Mesh(geom, mat);
    mesh.frustumCulled = false;
    scene.add(mesh);
    return { ids: ids, mesh: mesh, rings: rings };
  });

  function updateRod(rod) {
    var ids = rod.ids, n = ids.length;
    var geom = rod.mesh.geometry;
    var pos = geom.attributes.position.array, nor = geom.attributes.normal.array, col = geom.attributes.color.array;
    var p = ids.map(point), tang = [];
    for (var i = 0; i < n; ++i) {
      var a = p[Math.max(i - 1, 0)], b = p[Math.min(i + 1, n - 1)];
      tang.push(b.clone().sub(a).multiplyScalar(i > 0 && i < n - 1 ? 0.5 : 1));
    }
    var normal = new THREE.Vector3(), binormal = new THREE.Vector3(), c = new THREE.Color();
    var prevNormal = null, v = 0;
    for (var e = 0; e + 1 < Math.max(n, 2); ++e) {
      for (var s = e === 0 ? 0 : 1; s <= kSub; ++s) {
        var u = s / kSub, i0 = Math.min(e, n - 1), i1 = Math.min(e + 1, n - 1);
        // Cubic Hermite position and tangent between nodes i0 and i1.
        var h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u;
        var h01 = -2 * u * u * u + 3 * u * u, h11 = u * u * u - u * u;
        var x = p[i0].clone().multiplyScalar(h00).addScaledVector(tang[i0], h10)
          .addScaledVector(p[i1], h01).addScaledVector(tang[i1], h11);
        var d00 = 6 * u * u - 6 * u, d10 = 3 * u * u - 4 * u + 1, d01 = -d00, d11 = 3 * u * u - 2 * u;
        var t = p[i0].clone().multiplyScalar(d00).addScaledVector(tang[i0], d10)
          .addScaledVector(p[i1], d01).addScaledVector(tang[i1], d11);
        if (t.lengthSq() < 1e-24) t.copy(tang[i0]);
        if (t.lengthSq() < 1e-24) t.set(1, 0, 0);
        t.normalize();
        // Cross-section orientation: the nodes' frame y axes, interpolated, or carried along.
        if (axes) normal.copy(axis(ids[i0], 1)).multiplyScalar(1 - u).addScaledVector(axis(ids[i1], 1), u);
        else if (prevNormal) normal.copy(prevNormal);
        else normal.set(0, 0, 1);
        normal.addScaledVector(t, -normal.dot(t));
        if (normal.lengthSq() < 1e-12) {
          normal.set(Math.abs(t.x) < 0.9 ? 1 : 0, Math.abs(t.x) < 0.9 ? 0 : 1, 0);
          normal.addScaledVector(t, -normal.dot(t));
        }
        normal.normalize();
        prevNormal = normal.clone();
        binormal.crossVectors(t, normal);
        if (field) {
          var f = (1 - u) * curField[ids[i0]] + u * curField[ids[i1]];
          colormap((f - field.lo) / (field.hi - field.lo), c);
        } else {
          c.copy(rodColor);
        }
        for (var k = 0; k <= kRadial; ++k, ++v) {
          var ang = 2 * Math.PI * k / kRadial, cs = Math.cos(ang), sn = Math.sin(ang);
          var nx = cs * normal.x + sn * binormal.x, ny = cs * normal.y + sn * binormal.y, nz = cs * normal.z + sn * binormal.z;
          pos[3 * v] = x.x + tubeRadius * nx; pos[3 * v + 1] = x.y + tubeRadius * ny; pos[3 * v + 2] = x.z + tubeRadius * nz;
          nor[3 * v] = nx; nor[3 * v + 1] = ny; nor[3 * v + 2] = nz;
          col[3 * v] = c.r; col[3 * v + 1] = c.g; col[3 * v + 2] = c.b;
        }
      }
    }
    geom.attributes.position.needsUpdate = true;
    geom.attributes.normal.needsUpdate = true;
    geom.attributes.color.needsUpdate = true;
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

  // ---- rigid bodies: boxes along their segments, oriented by the body frame -----------------
  var unitBox = new THREE.BoxBufferGeometry(1, 1, 1);
  var bodyMaterial = new THREE.MeshStandardMaterial({ color: 0x8a94a6, roughness: 0.5, metalness: 0.2 });
  var bodies = data.bodies.map(function (b) {
    var meshes = b.segments.map(function () {
      var m = new THREE.Mesh(unitBox, bodyMaterial);
      m.matrixAutoUpdate = false;
      scene.add(m);
      return m;
    });
    var lump = null;
    if (b.vertex !== null) {
      lump = new THREE.Mesh(unitBox, bodyMaterial);
      lump.matrixAutoUpdate = false;
      scene.add(lump);
    }
    return { segments: b.segments, meshes: meshes, vertex: b.vertex, lump: lump };
  });

  function updateBody(body) {
    body.segments.forEach(function (seg, k) {
      var a = point(seg[0]), b = point(seg[1]);
      var x = b.clone().sub(a), len = x.length();
      x.normalize();
      // Roll: the body frame's axis most perpendicular to the segment.
      var y = new THREE.Vector3(0, 0, 1);
      if (axes) {
        var best = 2;
        for (var j = 0; j < 3; ++j) {
          var c = axis(seg[0], j), d = Math.abs(c.dot(x));
          if (d < best) { best = d; y.copy(c); }
        }
      }
      y.addScaledVector(x, -y.dot(x));
      if (y.lengthSq() < 1e-12) y.set(Math.abs(x.z) < 0.9 ? 0 : 1, 0, Math.abs(x.z) < 0.9 ? 1 : 0).addScaledVector(x, -x.z);
      y.normalize();
      var z = new THREE.Vector3().crossVectors(x, y);
      var m = body.meshes[k].matrix;
      m.makeBasis(x.multiplyScalar(len + bodyWidth), y.multiplyScalar(bodyWidth), z.multiplyScalar(bodyWidth));
      m.setPosition(a.add(b).multiplyScalar(0.5));
    });
    if (body.lump) {
      var s = 2 * bodyWidth;
      body.lump.matrix.makeScale(s, s, s).setPosition(point(body.vertex));
    }
  }

  // ---- joints: spheres (actuated orange, passive teal, welds grey) ---------------------------
  var sphere = new THREE.SphereBufferGeometry(1, 20, 14);
  var jointMaterials = {
    actuated: new THREE.MeshStandardMaterial({ color: 0xe07b24, roughness: 0.4 }),
    passive: new THREE.MeshStandardMaterial({ color: 0x17a589, roughness: 0.4 }),
    weld: new THREE.MeshStandardMaterial({ color: 0x59606b, roughness: 0.6 }),
  };
  var labels = new THREE.Group();
  scene.add(labels);
  // Joints at the same place (a hinge and a weld at one point) share one label, "J1, W1".
  var labelOwner = data.joints.map(function (j, k) {
    for (var i = 0; i < k; ++i)
      if (point0(data.joints[i].point).distanceTo(point0(j.point)) < 1e-6 * size) return i;
    return k;
  });
  function point0(i) { return new THREE.Vector3(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]); }
  var joints = data.joints.map(function (j, k) {
    var kind = j.type === "fixed" ? "weld" : j.drive && j.drive !== "none" ? "actuated" : "passive";
    var m = new THREE.Mesh(sphere, jointMaterials[kind]);
    var r = kind === "weld" ? 0.6 * jointRadius : jointRadius;
    m.scale.set(r, r, r);
    scene.add(m);
    var label = null;
    if (j.name && labelOwner[k] === k) {
      var names = data.joints.filter(function (o, i) { return labelOwner[i] === k && o.name; })
        .map(function (o) { return o.name; });
      label = textSprite(names.join(", "), "#1d2430", 0.03 * size0);
      labels.add(label);
    }
    return { point: j.point, mesh: m, label: label, name: j.name };
  });

  // ---- recorded points and their trails -------------------------------------------------------
  var recPoints = [];
  if (rec) {
    var recColors = [0xc2185b, 0x6a1b9a, 0xad1457, 0x4527a0, 0x880e4f];  // magentas and purples
    var nr = recTimes.length, npr = rec.names.length;
    rec.names.forEach(function (name, k) {
      var color = recColors[k % recColors.length];
      var m = new THREE.Mesh(sphere, new THREE.MeshStandardMaterial({ color: color, roughness: 0.4 }));
      var r = 0.75 * jointRadius;
      m.scale.set(r, r, r);
      scene.add(m);
      var trailPos = new Float32Array(nr * 3);
      for (var i = 0; i < nr; ++i)
        for (var c = 0; c < 3; ++c) trailPos[3 * i + c] = recXyz[3 * (i * npr + k) + c];
      var g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(trailPos, 3));
      var line = new THREE.Line(g, new THREE.LineBasicMaterial({ color: color, transparent: true, opacity: 0.75 }));
      line.frustumCulled = false;
      scene.add(line);
      var label = textSprite(name, "#" + new THREE.Color(color).getHexString(), 0.03 * size0);
      labels.add(label);
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
    if (b.vertex !== null) ids.push(b.vertex);
    targets.push({ name: b.name || "rigid body " + (k + 1), what: "body", center: function () { return centroid(ids); } });
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
  var projected = null;  // screen box of the mechanism in CSS pixels, for tests

  function update() {
    computeState(time);
    rods.forEach(updateRod);
    bodies.forEach(updateBody);
    joints.forEach(function (j) {
      j.mesh.position.copy(point(j.point));
      if (j.label) j.label.position.copy(j.mesh.position).addScaledVector(up, 2.2 * jointRadius);
    });
    recPoints.forEach(function (p) {
      var x = recordedPoint(p.k, time);
      p.mesh.position.copy(x);
      p.label.position.copy(x).addScaledVector(up, -2.4 * jointRadius);  // joints' labels go above
      var end = bracket(recTimes, time)[0] + 1;
      var start = trail === "all" ? 0 : bracket(recTimes, time - trail)[0];
      p.line.geometry.setDrawRange(start, trail === 0 || bare ? 0 : end - start);
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
        var dist = 0.6 * size0 / Math.tan(camera.fov * Math.PI / 360);
        controls.target.copy(c);
        camera.position.copy(c).addScaledVector(dir, dist);
      }
      followLast = c;
      controls.update();
    }
    document.getElementById("time").textContent =
      "t = " + time.toFixed(3) + " s  (" + t0.toFixed(3) + " to " + t1.toFixed(3) + " s)";
    var slider = document.getElementById("slider");
    if (document.activeElement !== slider || playing)
      slider.value = String(Math.round(1000 * (t1 > t0 ? (time - t0) / (t1 - t0) : 0)));
  }

  function resize() {
    var w = container.clientWidth || window.innerWidth, h = container.clientHeight || window.innerHeight;
    renderer.setSize(w, h, false);
    renderer.domElement.style.width = w + "px";
    renderer.domElement.style.height = h + "px";
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
  }

  function render() {
    renderer.render(scene, camera);
    // Screen box of the drawn points (the test compares it with the pixels).
    var w = renderer.domElement.clientWidth, h = renderer.domElement.clientHeight;
    var x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity, v = new THREE.Vector3();
    for (var i = 0; i < np; ++i) {
      v.set(cur[3 * i], cur[3 * i + 1], cur[3 * i + 2]).project(camera);
      var sx = (v.x + 1) / 2 * w, sy = (1 - v.y) / 2 * h;
      x0 = Math.min(x0, sx); x1 = Math.max(x1, sx); y0 = Math.min(y0, sy); y1 = Math.max(y1, sy);
    }
    projected = [x0, y0, x1, y1].map(function (q) { return Math.round(q); });
    document.body.setAttribute("data-time", time.toFixed(6));
    document.body.setAttribute("data-bbox", projected.join(","));
  }

  // ---- controls --------------------------------------------------------------------------
  var playButton = document.getElementById("play");
  function setPlaying(on) {
    playing = on && t1 > t0;
    playButton.textContent = playing ? "Pause" : "Play";
    last = null;
  }
  playButton.addEventListener("click", function () {
    if (!playing && time >= t1) time = t0;
    setPlaying(!playing);
  });
  document.getElementById("slider").addEventListener("input", function (e) {
    time = t0 + (t1 - t0) * Number(e.target.value) / 1000;
    update();
    render();
  });
  document.getElementById("speed").addEventListener("change", function (e) { speed = Number(e.target.value); });
  document.getElementById("trail").addEventListener("change", function (e) {
    trail = e.target.value === "all" ? "all" : Number(e.target.value);
    update(); render();
  });
  followSelect.addEventListener("change", function (e) { setFollow(e.target.value); update(); render(); });
  document.getElementById("labels").addEventListener("change", function (e) {
    labels.visible = e.target.checked; render();
  });
  document.getElementById("reset").addEventListener("click", function () {
    followSelect.value = ""; setFollow(null); frameAll(); update(); render();
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
    var legend = document.getElementById("legend");
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

  var last = null;
  function tick(now) {
    if (playing) {
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
    }
    requestAnimationFrame(tick);
  }

  // ---- start -------------------------------------------------------------------------------
  document.getElementById("case").textContent = data.name || "screwfem run";
  var notes = [];
  if (data.status && data.status !== "completed") notes.push("run " + data.status + (data.message ? ": " + data.message : ""));
  notes = notes.concat(data.notes || []);
  document.getElementById("note").textContent = notes.join(" \u00b7 ");
  labels.visible = !bare && params.get("labels") === "1";
  document.getElementById("labels").checked = labels.visible;
  if (bare) decor.visible = false;
  resize();
  frameAll();
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
  if (document.body.getAttribute("data-state") !== "error") document.body.setAttribute("data-state", "ready");
  if (!frozen) setPlaying(nf > 1);
  requestAnimationFrame(tick);
})();
