// The report's 3D replay (docs/report.md, "3D replay"): the robot drawn from its URDF geometry
// with three.js (Debian's libjs-three, copied beside the page), animated from a run's base pose
// and joint positions, with the targets, the contact forces as arrows and the CoM box.
//
// Data files are classic scripts loaded on demand (they work from file://, where fetch does
// not): replay/model_<robot>.js calls LexdynReplay.registerModel, replay/run_<id>.js calls
// LexdynReplay.registerRun.
(function () {
  "use strict";
  var R = (window.LexdynReplay = window.LexdynReplay || {});
  R.models = R.models || {};
  R.runs = R.runs || {};
  var pending = {};
  var view = null; // {renderer, scene, camera, controls, robot, run, time, playing, ...}

  // ---------------------------------------------------------------- data decoding
  function decodeChannel(ch, n) {
    var out = new Float64Array(n);
    if (ch.c !== undefined) {
      out.fill(ch.c === null ? NaN : ch.c);
      return out;
    }
    var bin = atob(ch.d);
    var bytes = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    var dv = new DataView(bytes.buffer);
    for (var k = 0; k < n; k++) {
      var q = dv.getInt16(2 * k, true);
      out[k] = q === -32768 ? NaN : ch.o + ch.s * q;
    }
    return out;
  }

  function decodeRun(data) {
    var n = data.frames;
    var cols = {};
    Object.keys(data.channels).forEach(function (name) {
      cols[name] = decodeChannel(data.channels[name], n);
    });
    data.cols = cols;
    return data;
  }

  R.registerModel = function (name, model) {
    R.models[name] = model;
    var cb = pending["model:" + name];
    if (cb) { delete pending["model:" + name]; cb(); }
  };

  R.registerRun = function (id, data) {
    R.runs[id] = decodeRun(data);
    var cb = pending["run:" + id];
    if (cb) { delete pending["run:" + id]; cb(); }
  };

  function loadScript(key, src, done) {
    pending[key] = done;
    var s = document.createElement("script");
    s.src = src;
    s.onerror = function () {
      delete pending[key];
      status("could not load " + src);
    };
    document.head.appendChild(s);
  }

  function status(text) {
    var el = document.getElementById("replay-status");
    if (el) el.textContent = text;
  }

  // ---------------------------------------------------------------- the robot
  function rpyEuler(rpy) { return new THREE.Euler(rpy[0], rpy[1], rpy[2], "ZYX"); }

  function visualMesh(model, v, fallbackColour) {
    var g = v.geom, geo;
    if (g.type === "box") geo = new THREE.BoxBufferGeometry(g.size[0], g.size[1], g.size[2]);
    else if (g.type === "sphere") geo = new THREE.SphereBufferGeometry(g.radius, 16, 12);
    else if (g.type === "cylinder") {
      geo = new THREE.CylinderBufferGeometry(g.radius, g.radius, g.length, 20);
      geo.rotateX(Math.PI / 2); // URDF cylinders lie along z, three.js ones along y
    } else if (g.type === "mesh") {
      var bin = atob(model.meshes[g.mesh]);
      var bytes = new Uint8Array(bin.length);
      for (var i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
      var dv = new DataView(bytes.buffer), n = bytes.length / 4, pos = new Float32Array(n);
      for (var k = 0; k < n; k++) pos[k] = dv.getFloat32(4 * k, true);
      geo = new THREE.BufferGeometry();
      geo.setAttribute("position", new THREE.BufferAttribute(pos, 3));
      geo.scale(g.scale[0], g.scale[1], g.scale[2]);
      geo.computeVertexNormals();
    } else return null;
    var c = v.rgba ? new THREE.Color(v.rgba[0], v.rgba[1], v.rgba[2]) : new THREE.Color(fallbackColour);
    var mat = new THREE.MeshLambertMaterial({color: c, transparent: !!(v.rgba && v.rgba[3] < 1),
                                             opacity: v.rgba ? v.rgba[3] : 1});
    var mesh = new THREE.Mesh(geo, mat);
    mesh.position.set(v.xyz[0], v.xyz[1], v.xyz[2]);
    mesh.setRotationFromEuler(rpyEuler(v.rpy));
    return mesh;
  }

  function buildRobot(model) {
    var base = new THREE.Group();
    var objs = {}, motions = {};
    var root = new THREE.Group();
    root.name = model.root;
    base.add(root);
    objs[model.root] = root;
    model.joints.forEach(function (j) {
      var origin = new THREE.Group();
      origin.position.set(j.xyz[0], j.xyz[1], j.xyz[2]);
      origin.setRotationFromEuler(rpyEuler(j.rpy));
      var m = new THREE.Group();
      m.name = j.child;
      origin.add(m);
      objs[j.parent].add(origin);
      objs[j.child] = m;
      if (j.type === "revolute" || j.type === "continuous" || j.type === "prismatic") {
        var a = new THREE.Vector3(j.axis[0], j.axis[1], j.axis[2]).normalize();
        motions[j.name] = {obj: m, axis: a, prismatic: j.type === "prismatic"};
      }
    });
    var shades = ["#b8c2cc", "#9aa7b4"];
    Object.keys(model.links).forEach(function (name, i) {
      var link = model.links[name], obj = objs[name];
      if (!obj) return;
      var drawn = 0;
      link.visuals.forEach(function (v) {
        var mesh = visualMesh(model, v, shades[i % 2]);
        if (mesh) { obj.add(mesh); drawn++; }
      });
      if (!drawn) {
        // No visual geometry: a marker, so that the link is still seen.
        var mk = new THREE.Mesh(new THREE.SphereBufferGeometry(0.04, 12, 8),
                                new THREE.MeshLambertMaterial({color: "#6c7a89"}));
        obj.add(mk);
      }
    });
    model.frames.forEach(function (f) {
      var o = new THREE.Group();
      o.name = f.name;
      o.position.set(f.xyz[0], f.xyz[1], f.xyz[2]);
      o.setRotationFromEuler(rpyEuler(f.rpy));
      if (objs[f.parent]) objs[f.parent].add(o);
      objs[f.name] = o;
    });
    return {base: base, objs: objs, motions: motions, model: model};
  }

  // ---------------------------------------------------------------- scene
  // Drawn over the robot's links (forces start inside the feet, the CoM is inside the body).
  function onTop(obj) {
    obj.material.depthTest = false;
    obj.material.transparent = true;
    obj.renderOrder = 10;
    return obj;
  }

  function arrow(colour) {
    var a = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.1, colour, 0.06, 0.035);
    onTop(a.line);
    onTop(a.cone);
    a.visible = false;
    return a;
  }

  function makeView(container) {
    var canvas = document.createElement("canvas");
    canvas.id = "replay-canvas";
    canvas.width = container.clientWidth || 900;
    canvas.height = Math.round(canvas.width * 0.56);
    container.appendChild(canvas);
    var renderer;
    try {
      renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: true, preserveDrawingBuffer: true});
    } catch (e) {
      container.removeChild(canvas);
      status("WebGL is not available in this browser: the 3D replay cannot be drawn (" + e.message + ")");
      return null;
    }
    renderer.setClearColor("#f4f6f8");
    var scene = new THREE.Scene();
    var camera = new THREE.PerspectiveCamera(40, canvas.width / canvas.height, 0.01, 100);
    camera.up.set(0, 0, 1);
    scene.add(new THREE.AmbientLight(0xffffff, 0.55));
    var sun = new THREE.DirectionalLight(0xffffff, 0.6);
    sun.position.set(2, -3, 4);
    scene.add(sun);
    var grid = new THREE.GridHelper(6, 24, 0x8899aa, 0xc8d0d8);
    grid.rotateX(Math.PI / 2);
    scene.add(grid);
    var controls = THREE.OrbitControls ? new THREE.OrbitControls(camera, canvas) : null;
    var v = {renderer: renderer, scene: scene, camera: camera, controls: controls, canvas: canvas,
             robot: null, run: null, time: 0, playing: false, speed: 1, extras: null};
    if (controls) controls.addEventListener("change", function () { render(v); });
    return v;
  }

  function render(v) { v.renderer.render(v.scene, v.camera); }

  function clearRun(v) {
    if (v.robot) v.scene.remove(v.robot.base);
    if (v.extras) v.scene.remove(v.extras.group);
    v.robot = null;
    v.extras = null;
  }

  function buildExtras(run) {
    var g = new THREE.Group();
    var ex = {group: g, targets: [], contacts: [], surfaces: [], com: null, box: null};
    run.targets.forEach(function (t) {
      var m = new THREE.Mesh(new THREE.SphereBufferGeometry(0.03, 12, 8),
                             new THREE.MeshLambertMaterial({color: t.kind === "com" ? "#8e44ad" : "#e91e63"}));
      var lineGeo = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]);
      var line = new THREE.Line(lineGeo, new THREE.LineBasicMaterial({color: "#e91e63"}));
      line.visible = false;
      g.add(m);
      g.add(line);
      ex.targets.push({spec: t, mesh: m, line: line});
    });
    if (run.cols["com.x"]) {
      ex.com = onTop(new THREE.Mesh(new THREE.SphereBufferGeometry(0.025, 12, 8), new THREE.MeshBasicMaterial({color: "#222222"})));
      g.add(ex.com);
    }
    if (run.box) {
      var edges = new THREE.EdgesGeometry(new THREE.BoxBufferGeometry(1, 1, 1));
      ex.box = new THREE.LineSegments(edges, new THREE.LineBasicMaterial({color: "#8e44ad"}));
      g.add(ex.box);
    }
    run.contacts.forEach(function (c) {
      var e = {spec: c, sensed: arrow(0xd35400), computed: arrow(0x2980b9)};
      g.add(e.sensed);
      g.add(e.computed);
      ex.contacts.push(e);
    });
    run.surfaces.forEach(function (s) {
      var e = {spec: s, arrow: arrow(0xd35400)};
      g.add(e.arrow);
      ex.surfaces.push(e);
    });
    return ex;
  }

  // Value of channel NAME at fractional frame F (linear between frames).
  function val(run, name, f) {
    var c = run.cols[name];
    if (!c) return NaN;
    var i = Math.floor(f), a = f - i;
    if (i >= run.frames - 1) return c[run.frames - 1];
    if (i < 0) return c[0];
    return a === 0 ? c[i] : c[i] * (1 - a) + c[i + 1] * a;
  }

  var tmpV = new THREE.Vector3(), tmpQ = new THREE.Quaternion();

  function setArrow(a, origin, force) {
    var n = force.length();
    if (!(n >= 1.0)) { a.visible = false; return; }
    var len = Math.min(2.0, n * 0.001); // 1 mm per N
    a.position.copy(origin);
    a.setDirection(force.clone().divideScalar(n));
    a.setLength(len, Math.min(0.08, 0.3 * len), Math.min(0.05, 0.18 * len));
    a.visible = true;
  }

  function applyFrame(v, f) {
    var run = v.run, rb = v.robot;
    if (run.base) {
      rb.base.position.set(val(run, "base.x", f), val(run, "base.y", f), val(run, "base.z", f));
      // Body-fixed X-Y-Z Euler angles: R = Rx(rx) Ry(ry) Rz(rz) (docs/model.md).
      rb.base.setRotationFromEuler(new THREE.Euler(val(run, "base.rx", f), val(run, "base.ry", f), val(run, "base.rz", f), "XYZ"));
    }
    run.joints.forEach(function (name) {
      var m = rb.motions[name];
      if (!m) return;
      var q = val(run, "q." + name, f);
      if (!isFinite(q)) return;
      if (m.prismatic) m.obj.position.copy(m.axis).multiplyScalar(q);
      else m.obj.quaternion.setFromAxisAngle(m.axis, q);
    });
    rb.base.updateMatrixWorld(true);
    var ex = v.extras;
    ex.targets.forEach(function (t) {
      var n = t.spec.task;
      var p = new THREE.Vector3(val(run, "target." + n + ".x", f), val(run, "target." + n + ".y", f), val(run, "target." + n + ".z", f));
      t.mesh.visible = isFinite(p.x + p.y + p.z);
      t.mesh.position.copy(p);
      var from = null;
      if (t.spec.frame && rb.objs[t.spec.frame]) from = rb.objs[t.spec.frame].getWorldPosition(new THREE.Vector3());
      else if (t.spec.kind === "com" && run.cols["com.x"]) from = new THREE.Vector3(val(run, "com.x", f), val(run, "com.y", f), val(run, "com.z", f));
      if (from && t.mesh.visible) {
        t.line.geometry.setFromPoints([from, p]);
        t.line.visible = true;
      } else t.line.visible = false;
    });
    if (ex.com) ex.com.position.set(val(run, "com.x", f), val(run, "com.y", f), val(run, "com.z", f));
    if (ex.box) {
      var b = run.box.task, lo = [], hi = [];
      ["x", "y", "z"].forEach(function (a) {
        lo.push(val(run, "target." + b + ".lower_" + a, f));
        hi.push(val(run, "target." + b + ".upper_" + a, f));
      });
      ex.box.scale.set(Math.max(1e-4, hi[0] - lo[0]), Math.max(1e-4, hi[1] - lo[1]), Math.max(1e-4, hi[2] - lo[2]));
      ex.box.position.set(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    }
    ex.contacts.forEach(function (c) {
      var frame = c.spec.frame && rb.objs[c.spec.frame];
      var active = run.cols[c.spec.active] ? val(run, c.spec.active, Math.round(f)) > 0.5 : true;
      [["sensed", c.sensed], ["computed", c.computed]].forEach(function (kv) {
        var keys = c.spec[kv[0]];
        if (!keys || !frame || !active) { kv[1].visible = false; return; }
        var w = keys.map(function (k) { return val(run, k, f); });
        // Wrenches are in the contact frame's axes about its origin (docs/cases.md); the
        // arrow starts at the centre of pressure (-ty/fz, tx/fz) when the force is normal.
        var local = new THREE.Vector3(0, 0, 0);
        if (Math.abs(w[2]) > 1.0) local.set(-w[4] / w[2], w[3] / w[2], 0).clampLength(0, 0.5);
        var origin = frame.localToWorld(local.clone());
        frame.getWorldQuaternion(tmpQ);
        var force = new THREE.Vector3(w[0], w[1], w[2]).applyQuaternion(tmpQ);
        setArrow(kv[1], origin, force);
      });
    });
    ex.surfaces.forEach(function (s) {
      var fz = val(run, s.spec.fz, f), x = 0, y = 0;
      s.spec.points.forEach(function (p) { x += val(run, p[0], f); y += val(run, p[1], f); });
      x /= s.spec.points.length;
      y /= s.spec.points.length;
      setArrow(s.arrow, new THREE.Vector3(x, y, 0), new THREE.Vector3(0, 0, fz));
    });
  }

  function frameCamera(v) {
    var box = new THREE.Box3().setFromObject(v.robot.base);
    var c = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3());
    var r = Math.max(0.3, size.length());
    v.camera.position.set(c.x + 0.85 * r, c.y - 1.15 * r, c.z + 0.45 * r);
    v.camera.lookAt(c);
    if (v.controls) { v.controls.target.copy(c); v.controls.update(); }
  }

  function timeAt(run, f) { return val(run, "t", f); }

  function updateReadout(v) {
    var run = v.run, el = document.getElementById("replay-time");
    if (el) el.textContent = "t = " + timeAt(run, v.frame).toFixed(3) + " s  (frame " + Math.round(v.frame) + " of " + (run.frames - 1) + ", every " + run.every + " trace rows)";
    var sl = document.getElementById("replay-slider");
    if (sl && document.activeElement !== sl) sl.value = String(v.frame);
  }

  // ---------------------------------------------------------------- API
  R.setFrame = function (f) {
    if (!view || !view.run) return;
    view.frame = Math.max(0, Math.min(view.run.frames - 1, Number(f)));
    applyFrame(view, view.frame);
    render(view);
    updateReadout(view);
  };

  // World position of a link or data-file frame at the frame shown (tests compare it with
  // the simulator's frame.<F>.x/y/z channels).
  R.framePosition = function (name) {
    if (!view || !view.robot || !view.robot.objs[name]) return null;
    var p = view.robot.objs[name].getWorldPosition(new THREE.Vector3());
    return [p.x, p.y, p.z];
  };

  R.current = function () { return view && view.run ? {id: view.run.id, frame: view.frame, frames: view.run.frames} : null; };

  function showLoaded(id) {
    var run = R.runs[id], model = R.models[run.model];
    clearRun(view);
    view.run = run;
    view.robot = buildRobot(model);
    view.extras = buildExtras(run);
    view.scene.add(view.robot.base);
    view.scene.add(view.extras.group);
    var sl = document.getElementById("replay-slider");
    if (sl) { sl.max = String(run.frames - 1); sl.value = "0"; }
    view.frame = 0;
    applyFrame(view, 0);
    frameCamera(view);
    R.setFrame(0);
    status("");
    var sel = document.getElementById("replay-run");
    if (sel) sel.value = id;
    var info = document.getElementById("replay-info");
    if (info) info.textContent = run.case + (run.method ? " / " + run.method : "") + ": " + run.rows + " trace rows, " + run.frames + " frames";
    if (R.onshow) R.onshow(id);
  }

  // Shows run ID, loading its data (and its robot's) first; CALLBACK when drawn.
  R.show = function (id, callback) {
    if (!view) { status("the 3D replay is not available"); return; }
    var entry = (R.index || {})[id];
    if (!entry) { status("no replay for " + id); return; }
    var done = function () { showLoaded(id); if (callback) callback(); };
    var needRun = function () {
      if (R.runs[id]) done();
      else { status("loading " + id + " ..."); loadScript("run:" + id, entry.run, done); }
    };
    if (R.models[entry.model_name]) needRun();
    else loadScript("model:" + entry.model_name, entry.model, needRun);
  };

  R.play = function (on) {
    if (!view || !view.run) return;
    view.playing = on === undefined ? !view.playing : !!on;
    var btn = document.getElementById("replay-play");
    if (btn) btn.textContent = view.playing ? "pause" : "play";
    if (!view.playing) return;
    var last = null;
    var step = function (now) {
      if (!view.playing) return;
      if (last !== null) {
        var run = view.run, t = timeAt(run, view.frame) + view.speed * (now - last) / 1000;
        var tEnd = timeAt(run, run.frames - 1);
        if (t >= tEnd) { R.setFrame(run.frames - 1); R.play(false); return; }
        // The frame at time t (frames are evenly spaced but for the last one).
        var f = view.frame;
        while (f < run.frames - 1 && timeAt(run, Math.floor(f) + 1) <= t) f = Math.floor(f) + 1;
        var i = Math.floor(f), t0 = timeAt(run, i), t1 = timeAt(run, Math.min(run.frames - 1, i + 1));
        R.setFrame(i + (t1 > t0 ? (t - t0) / (t1 - t0) : 0));
      }
      last = now;
      requestAnimationFrame(step);
    };
    requestAnimationFrame(step);
  };

  R.init = function (index) {
    R.index = index;
    var container = document.getElementById("replay-view");
    if (!container) return;
    if (typeof THREE === "undefined") { status("three.js did not load (three.min.js beside the page)"); return; }
    view = makeView(container);
    if (!view) return;
    var sel = document.getElementById("replay-run");
    sel.addEventListener("change", function () { R.play(false); R.show(sel.value); });
    var sl = document.getElementById("replay-slider");
    sl.addEventListener("input", function () { R.setFrame(Number(sl.value)); });
    document.getElementById("replay-play").addEventListener("click", function () { R.play(); });
    var sp = document.getElementById("replay-speed");
    sp.addEventListener("change", function () { view.speed = Number(sp.value); });
    view.speed = Number(sp.value);
    Array.prototype.forEach.call(document.querySelectorAll("[data-replay]"), function (a) {
      a.addEventListener("click", function () { R.play(false); R.show(a.getAttribute("data-replay")); });
    });
    if (sel.value) R.show(sel.value);
  };
})();
