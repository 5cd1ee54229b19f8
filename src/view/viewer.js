// The lsdc viewer: the mechanism in 3D (three.js), an animation with a time slider, plots of
// chosen series, and, when served by `lsdc view`, simulations run on demand and bodies dragged
// with the mouse. `#status` holds a JSON summary of the page's state for tests.
"use strict";
(function () {
  const read = (id) => JSON.parse(document.getElementById(id).textContent);
  const scene = read("scene-data");
  let animation = read("animation-data");
  const mode = read("mode-data");
  const params = new URLSearchParams(location.search);
  // `frame`/`time`: the output shown; `furthest`: the latest output shown so far; `last`: the
  // animation's last output; `laps`: how many times playing went round from the end to the start.
  const status = { ready: false, objects: 0, bodies: 0, joints: 0, complementary: 0, frames: 0,
                   frame: 0, time: 0, furthest: 0, last: 0, end: 0, laps: 0, failure: null,
                   advanced: false, playing: false, drag: null, error: null };
  window.lsdcStatus = status;
  const report = () => { document.getElementById("status").textContent = JSON.stringify(status); };
  const message = (text) => {
    const box = document.getElementById("message");
    box.textContent = text;
    box.style.display = text ? "block" : "none";
  };

  if (!window.THREE) {
    status.error = "three.js is missing";
    report();
    return;
  }
  const view = document.getElementById("view");
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    status.error = "no WebGL: " + e.message;
    report();
    return;
  }
  renderer.setClearColor(0xf4f4f2);
  view.appendChild(renderer.domElement);
  const world = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(40, 1, 0.001, 1e4);
  camera.up.set(0, 0, 1);
  world.add(new THREE.HemisphereLight(0xffffff, 0x777777, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.5);
  sun.position.set(1, -2, 3);
  world.add(sun);

  // The size of the mechanism: every body point in the first configuration.
  const worldPoint = (pose, p) => {
    const v = new THREE.Vector3(p[0], p[1], p[2]);
    v.applyQuaternion(new THREE.Quaternion(pose[4], pose[5], pose[6], pose[3]));
    return v.add(new THREE.Vector3(pose[0], pose[1], pose[2]));
  };
  const bounds = new THREE.Box3();
  bounds.expandByPoint(new THREE.Vector3(0, 0, 0));
  scene.bodies.forEach((body, i) => {
    bounds.expandByPoint(worldPoint(scene.poses[i], [0, 0, 0]));
    body.points.forEach((p) => bounds.expandByPoint(worldPoint(scene.poses[i], p)));
  });
  // The workspace's points are in view too.
  if (scene.workspace) scene.workspace.points.forEach((p) => bounds.expandByPoint(new THREE.Vector3(...p)));
  const centre = bounds.getCenter(new THREE.Vector3());
  const radius = Math.max(bounds.getSize(new THREE.Vector3()).length() / 2, 0.05);
  const thickness = radius * 0.025;

  // Earth: a grid in the plane z = 0 and the fixed axes.
  const grid = new THREE.GridHelper(4 * radius, 20, 0x999999, 0xcccccc);
  grid.rotation.x = Math.PI / 2;
  world.add(grid);
  const earthAxes = new THREE.AxesHelper(radius * 0.3);
  world.add(earthAxes);
  const groups = [earthAxes];  // groups[j]: what moves with body j (0: earth)
  const earth = new THREE.Group();
  world.add(earth);
  groups[0] = earth;

  const palette = [0x4e79a7, 0xf28e2b, 0x59a14f, 0xb07aa1, 0x76b7b2, 0xedc948, 0x9c755f, 0xff9da7];
  const pickable = [];
  const frameHelpers = [];
  const axisMeshes = [];
  const ellipsoids = [];

  function rod(from, to, radiusOfRod, material) {
    const a = new THREE.Vector3(...from);
    const b = new THREE.Vector3(...to);
    const length = a.distanceTo(b);
    if (length < 1e-9) return null;
    const mesh = new THREE.Mesh(new THREE.CylinderGeometry(radiusOfRod, radiusOfRod, length, 12), material);
    mesh.position.copy(a.clone().add(b).multiplyScalar(0.5));
    mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), b.clone().sub(a).normalize());
    return mesh;
  }

  scene.bodies.forEach((body, i) => {
    const group = new THREE.Group();
    const material = new THREE.MeshStandardMaterial({ color: palette[i % palette.length], roughness: 0.6 });
    const parts = [];
    const points = body.points.length > 0 ? body.points : [[0, 0, 0]];
    points.slice(1).forEach((p) => parts.push(rod(points[0], p, thickness, material)));
    if (points.length === 1) parts.push(rod(points[0], body.com, thickness, material));
    const hub = new THREE.Mesh(new THREE.SphereGeometry(thickness * 1.4, 16, 12), material);
    hub.position.set(...points[0]);
    parts.push(hub);
    parts.filter((m) => m).forEach((m) => {
      m.userData.body = body.number;
      pickable.push(m);
      group.add(m);
    });
    if (body.ellipsoid) {
      const shape = new THREE.Mesh(new THREE.SphereGeometry(1, 24, 16),
        new THREE.MeshStandardMaterial({ color: material.color, transparent: true, opacity: 0.35 }));
      const [a, b, c] = body.ellipsoid.semi_axes;
      shape.scale.set(Math.max(a, 1e-6), Math.max(b, 1e-6), Math.max(c, 1e-6));
      const [w, x, y, z] = body.ellipsoid.orientation;
      shape.quaternion.set(x, y, z, w);
      shape.position.set(...body.com);
      shape.visible = false;
      ellipsoids.push(shape);
      group.add(shape);
    }
    world.add(group);
    groups[body.number] = group;
  });

  // Joints: a cylinder along a revolute's axis, a bar along a prismatic's, a ball otherwise;
  // the complementary links (those that close loops) in red.
  scene.joints.forEach((joint) => {
    const colour = joint.complementary ? 0xd62728 : 0x555555;
    const material = new THREE.MeshStandardMaterial({ color: colour, roughness: 0.4 });
    let mesh;
    if (joint.axis && joint.kind === "revolute") {
      mesh = new THREE.Mesh(new THREE.CylinderGeometry(thickness * 1.8, thickness * 1.8, thickness * 6, 16), material);
    } else if (joint.axis) {
      mesh = new THREE.Mesh(new THREE.BoxGeometry(thickness * 2, thickness * 12, thickness * 2), material);
    } else {
      mesh = new THREE.Mesh(new THREE.SphereGeometry(thickness * 2.2, 16, 12), material);
    }
    mesh.position.set(...joint.position);
    if (joint.axis) {
      mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), new THREE.Vector3(...joint.axis).normalize());
      axisMeshes.push(mesh);
    }
    mesh.name = joint.name;
    groups[joint.first_body].add(mesh);
  });

  scene.frames.forEach((frame) => {
    const helper = new THREE.AxesHelper(radius * 0.15);
    helper.position.set(...frame.position);
    const [w, x, y, z] = frame.orientation;
    helper.quaternion.set(x, y, z, w);
    helper.name = frame.name;
    frameHelpers.push(helper);
    groups[frame.body].add(helper);
  });

  // The workspace (`lsdc view --workspace`): its reachable points coloured by dexterity (the
  // colours come with the scene, on the scale of `lsdc workspace --plot`), its boundary and its
  // singular loci, each a layer of dots of a constant size on the screen.
  const workspaceLayers = {};
  function dots(points, size, colour, colours) {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.Float32BufferAttribute(points.flat(), 3));
    const material = new THREE.PointsMaterial({ size, sizeAttenuation: false });
    if (colours) {
      // The scene's colours are sRGB; three.js keeps vertex colours linear.
      const linear = colours.flatMap(([r, g, b]) => new THREE.Color().setRGB(r / 255, g / 255, b / 255, THREE.SRGBColorSpace).toArray());
      geometry.setAttribute("color", new THREE.Float32BufferAttribute(linear, 3));
      material.vertexColors = true;
    } else {
      material.color = new THREE.Color(colour);
    }
    const layer = new THREE.Points(geometry, material);
    world.add(layer);
    return layer;
  }
  const workspace = scene.workspace;
  document.getElementById("workspace-tools").style.display = workspace ? "" : "none";
  if (workspace) {
    workspaceLayers.workspace = dots(workspace.points, 6, null, workspace.colours);
    workspaceLayers.boundary = dots(workspace.boundary.map((k) => workspace.points[k]), 8, 0x000000, null);
    workspaceLayers.singular = dots(workspace.singular, 10, 0xd62728, null);
    workspaceLayers.boundary.visible = false;
    const [best, worst] = workspace.dexterity || [null, null];
    document.getElementById("workspace-scale").textContent = workspace.title + (best === null ? "" :
      ": dexterity from " + best.toPrecision(4) + " (yellow) to " + worst.toPrecision(4) + " (purple), grey where singular");
    status.workspace = { points: workspace.points.length, boundary: workspace.boundary.length, singular: workspace.singular.length };
  }
  const showLayers = () => {
    if (!status.workspace) return;
    Object.entries(workspaceLayers).forEach(([name, layer]) => { status.workspace[name + "_shown"] = layer.visible; });
  };
  [["show-workspace", "workspace"], ["show-boundary", "boundary"], ["show-singular", "singular"]].forEach(([id, name]) => {
    document.getElementById(id).addEventListener("change", (e) => {
      if (workspaceLayers[name]) workspaceLayers[name].visible = e.target.checked;
      showLayers();
    });
  });
  showLayers();

  status.bodies = scene.bodies.length;
  status.joints = scene.joints.length;
  status.complementary = scene.joints.filter((j) => j.complementary).length;
  status.frames = scene.frames.length;
  let meshes = 0;
  world.traverse((o) => { if (o.isMesh || o.isLine) meshes += 1; });
  status.objects = meshes;

  function applyPoses(poses) {
    poses.forEach((pose, i) => {
      const group = groups[i + 1];
      group.position.set(pose[0], pose[1], pose[2]);
      group.quaternion.set(pose[4], pose[5], pose[6], pose[3]);
    });
  }
  let coordinates = scene.coordinates.slice();
  applyPoses(scene.poses);

  // Orbit (left button), pan (right button or shift), zoom (wheel), about `target`, z up.
  const orbit = { target: centre.clone(), distance: radius * 2.6, azimuth: -Math.PI / 3, elevation: 0.5 };
  function placeCamera() {
    const e = orbit.elevation, a = orbit.azimuth;
    const offset = new THREE.Vector3(Math.cos(e) * Math.cos(a), Math.cos(e) * Math.sin(a), Math.sin(e));
    camera.position.copy(orbit.target).addScaledVector(offset, orbit.distance);
    camera.lookAt(orbit.target);
  }
  let gesture = null;
  const canvas = renderer.domElement;
  canvas.addEventListener("contextmenu", (event) => event.preventDefault());
  canvas.addEventListener("pointerdown", (event) => {
    canvas.setPointerCapture(event.pointerId);
    if (dragEnabled() && event.button === 0 && !event.shiftKey && startDrag(event)) return;
    gesture = { x: event.clientX, y: event.clientY, pan: event.button === 2 || event.shiftKey };
  });
  canvas.addEventListener("pointermove", (event) => {
    if (dragging) { moveDrag(event); return; }
    if (!gesture) return;
    const dx = event.clientX - gesture.x, dy = event.clientY - gesture.y;
    gesture.x = event.clientX;
    gesture.y = event.clientY;
    if (gesture.pan) {
      const scale = orbit.distance / canvas.clientHeight;
      const right = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 0);
      const up = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 1);
      orbit.target.addScaledVector(right, -dx * scale).addScaledVector(up, dy * scale);
    } else {
      orbit.azimuth -= dx * 0.008;
      orbit.elevation = Math.max(-1.55, Math.min(1.55, orbit.elevation + dy * 0.008));
    }
    placeCamera();
  });
  canvas.addEventListener("pointerup", () => { gesture = null; dragging = null; });
  canvas.addEventListener("wheel", (event) => {
    event.preventDefault();
    orbit.distance *= Math.exp(event.deltaY * 0.001);
    placeCamera();
  }, { passive: false });

  function resize() {
    const width = view.clientWidth, height = view.clientHeight;
    renderer.setSize(width, height);
    camera.aspect = width / Math.max(height, 1);
    camera.updateProjectionMatrix();
    drawPlot();
  }

  // Animation: the slider picks an output; playing advances the time at the chosen speed.
  const slider = document.getElementById("slider");
  const playButton = document.getElementById("play");
  let clock = { playing: false, time: 0, last: 0 };
  function outputAt(time) {
    const times = animation.times;
    let lo = 0, hi = times.length - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (times[mid] <= time) lo = mid; else hi = mid - 1;
    }
    return lo;
  }
  function show(index) {
    if (!animation || animation.times.length === 0) return;
    applyPoses(animation.poses[index]);
    slider.value = index;
    status.frame = index;
    status.time = animation.times[index];
    status.advanced = status.advanced || index > 0;
    status.furthest = Math.max(status.furthest, index);
    document.getElementById("time").textContent = "t = " + animation.times[index].toFixed(3) + " s";
    drawPlot();
  }
  function loadAnimation(next) {
    animation = next;
    slider.max = Math.max(animation.times.length - 1, 0);
    status.last = Math.max(animation.times.length - 1, 0);
    status.end = animation.times.length > 0 ? animation.times[status.last] : 0;
    status.failure = animation.failure || null;
    status.furthest = 0;
    status.laps = 0;
    clock.time = 0;
    fillSeries();
    show(0);
    if (animation.failure) message("the run stopped early: " + animation.failure);
  }
  slider.addEventListener("input", () => {
    if (!animation) return;
    clock.time = animation.times[+slider.value];
    show(+slider.value);
  });
  function setPlaying(playing) {
    clock.playing = playing && !!animation && animation.times.length > 1;
    clock.last = performance.now();
    status.playing = clock.playing;
    playButton.textContent = clock.playing ? "Pause" : "Play";
  }
  playButton.addEventListener("click", () => setPlaying(!clock.playing));
  // The clock runs on a timer (which a headless browser's virtual time drives as well),
  // the drawing on animation frames.
  function advance() {
    const now = performance.now();
    if (clock.playing) {
      const speed = +document.getElementById("speed").value;
      clock.time += (now - clock.last) / 1000 * speed;
      const end = animation.times[animation.times.length - 1];
      // Past the end: the last output is shown once, then playing starts again from the start.
      if (clock.time > end && status.frame !== status.last) {
        clock.time = end;
      } else if (clock.time > end) {
        clock.time = 0;
        status.laps += 1;
      }
      show(outputAt(clock.time));
    }
    clock.last = now;
    report();
  }
  function tick() {
    renderer.render(world, camera);
    requestAnimationFrame(tick);
  }

  // Plots: the chosen series over time, on separate axes or normalised on one, with the
  // current time as a vertical line.
  const seriesList = document.getElementById("series");
  const plot = document.getElementById("plot");
  function fillSeries() {
    seriesList.innerHTML = "";
    if (!animation) return;
    animation.series.forEach((series, i) => {
      const option = document.createElement("option");
      option.value = i;
      option.textContent = series.name;
      option.selected = i === 0 || series.name === "energy";
      seriesList.appendChild(option);
    });
  }
  seriesList.addEventListener("change", () => drawPlot());
  document.querySelectorAll("input[name=plot-mode]").forEach((r) => r.addEventListener("change", () => drawPlot()));
  // A series' vertical axis. One whose relative variation is below `FLAT` (an energy conserved
  // to round-off, drift 2e-10) is drawn flat with its value, not as magnified noise or a
  // "decline" from 172 to 172; any other spans its values, labelled with the digits that tell
  // its ends apart.
  const FLAT = 1e-9;
  function valueAxis(values) {
    const lo = Math.min(...values), hi = Math.max(...values);
    const magnitude = Math.max(Math.abs(lo), Math.abs(hi));
    const variation = magnitude > 0 ? (hi - lo) / magnitude : 0;
    if (!(hi - lo > FLAT * magnitude)) {
      const mean = values.reduce((a, b) => a + b, 0) / values.length;
      return { flat: true, lo, hi, variation, low: mean.toPrecision(10), high: mean.toPrecision(10) };
    }
    const digits = Math.min(Math.max(Math.ceil(Math.log10(magnitude / (hi - lo))) + 2, 3), 15);
    return { flat: false, lo, hi, variation, low: lo.toPrecision(digits), high: hi.toPrecision(digits) };
  }
  function drawPlot() {
    const width = plot.clientWidth, height = plot.clientHeight;
    plot.width = width;
    plot.height = height;
    const g = plot.getContext("2d");
    g.clearRect(0, 0, width, height);
    if (!animation || animation.times.length < 2) return;
    const chosen = Array.from(seriesList.selectedOptions).map((o) => animation.series[+o.value]);
    status.plot = [];
    if (chosen.length === 0) return;
    const normalised = document.querySelector("input[name=plot-mode]:checked").value === "normalised";
    const times = animation.times, t0 = times[0], t1 = times[times.length - 1];
    const left = 70, right = width - 10;
    const x = (t) => left + (t - t0) / (t1 - t0 || 1) * (right - left);
    const bands = normalised ? 1 : chosen.length;
    const bandHeight = (height - 20) / bands;
    g.font = "11px sans-serif";
    chosen.forEach((series, k) => {
      const band = normalised ? 0 : k;
      const top = 5 + band * bandHeight, bottom = top + bandHeight - 8;
      const axis = valueAxis(series.values);
      const y = (v) => (axis.flat ? (top + bottom) / 2 : bottom - (v - axis.lo) / (axis.hi - axis.lo) * (bottom - top));
      g.strokeStyle = "#" + palette[k % palette.length].toString(16).padStart(6, "0");
      g.beginPath();
      series.values.forEach((v, i) => (i ? g.lineTo(x(times[i]), y(v)) : g.moveTo(x(times[i]), y(v))));
      g.stroke();
      g.fillStyle = g.strokeStyle;
      const range = axis.flat ? `= ${axis.low} (constant to ${axis.variation.toExponential(0)})` : `[${axis.low}, ${axis.high}]`;
      const label = normalised ? series.name : `${series.name} ${range}`;
      g.fillText(label, left + 4, top + 10 + (normalised ? 12 * k : 0));
      if (!normalised) {
        g.fillStyle = "#666";
        g.fillText(axis.flat ? axis.low : axis.high, 4, axis.flat ? (top + bottom) / 2 : top + 8);
        if (!axis.flat) g.fillText(axis.low, 4, bottom);
      }
      status.plot.push({ name: series.name, flat: axis.flat, low: axis.low, high: axis.high });
    });
    g.strokeStyle = "#000";
    g.beginPath();
    g.moveTo(x(status.time), 0);
    g.lineTo(x(status.time), height);
    g.stroke();
  }

  document.getElementById("show-frames").addEventListener("change", (e) => {
    frameHelpers.forEach((h) => { h.visible = e.target.checked; });
  });
  document.getElementById("show-axes").addEventListener("change", (e) => {
    axisMeshes.forEach((m) => { m.visible = e.target.checked; });
  });
  document.getElementById("show-ellipsoids").addEventListener("change", (e) => {
    ellipsoids.forEach((m) => { m.visible = e.target.checked; });
  });

  // Served pages only: simulations on demand and dragging through the server.
  document.getElementById("live-tools").style.display = mode.live ? "" : "none";
  document.getElementById("run").addEventListener("click", async () => {
    message("running…");
    const duration = +document.getElementById("duration").value;
    const response = await fetch("/api/simulate?duration=" + encodeURIComponent(duration));
    const body = await response.json();
    if (!response.ok) { message(body.error); return; }
    message("");
    loadAnimation(body);
    setPlaying(true);
  });
  const dragEnabled = () => mode.live && document.getElementById("drag").checked;
  let dragging = null;
  let pending = false;
  const raycaster = new THREE.Raycaster();
  function pointerRay(event) {
    const rect = canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2((event.clientX - rect.left) / rect.width * 2 - 1,
      -(event.clientY - rect.top) / rect.height * 2 + 1);
    raycaster.setFromCamera(ndc, camera);
  }
  function startDrag(event) {
    pointerRay(event);
    const hit = raycaster.intersectObjects(pickable, false)[0];
    if (!hit) return false;
    const body = hit.object.userData.body;
    const local = groups[body].worldToLocal(hit.point.clone());
    const normal = camera.getWorldDirection(new THREE.Vector3());
    dragging = { body, local, plane: new THREE.Plane().setFromNormalAndCoplanarPoint(normal, hit.point) };
    setPlaying(false);
    return true;
  }
  function moveDrag(event) {
    pointerRay(event);
    const target = new THREE.Vector3();
    if (raycaster.ray.intersectPlane(dragging.plane, target)) dragTo(dragging.body, dragging.local, target);
  }
  // The penalty method's bodies (X, Y, Θ) between moves; a new method starts from the
  // configuration shown.
  let planarState = null;
  const dragMethod = () => document.getElementById("drag-method").value;
  document.getElementById("drag-method").addEventListener("change", () => { planarState = null; });
  const dragRequest = (body, local, target) => JSON.stringify({
    body, point: [local.x, local.y, local.z], target: [target.x, target.y, target.z], coordinates,
    method: dragMethod(), planar: dragMethod() === "penalty" ? planarState : null });
  // The server's answer to a move: the new configuration, or why not.
  function applyDrag(ok, result) {
    if (!ok) { message(result.error); return null; }
    coordinates = result.coordinates;
    planarState = result.planar || null;
    applyPoses(result.poses);
    message(result.reached ? "" : "out of reach: " + result.distance.toPrecision(3) + " away");
    return result;
  }
  // One request at a time: moves while one is out are dropped, the next move catches up.
  async function dragTo(body, local, target) {
    if (pending) return null;
    pending = true;
    try {
      const response = await fetch("/api/drag", {
        method: "POST", headers: { "Content-Type": "application/json" }, body: dragRequest(body, local, target) });
      return applyDrag(response.ok, await response.json());
    } finally {
      pending = false;
    }
  }

  // `?drag-test=1`: drags the last body's last point by a tenth of the mechanism's size and
  // records how far it moved, for the browser tests. The request is synchronous so that the
  // page has its answer before it finishes loading (when a headless browser reads it).
  function dragTest() {
    const body = scene.bodies[scene.bodies.length - 1];
    const point = body.points[body.points.length - 1] || body.com;
    const local = new THREE.Vector3(...point);
    const before = groups[body.number].localToWorld(local.clone());
    const target = before.clone().add(new THREE.Vector3(0.1 * radius, 0.1 * radius, 0));
    const request = new XMLHttpRequest();
    request.open("POST", "/api/drag", false);
    request.setRequestHeader("Content-Type", "application/json");
    request.send(dragRequest(body.number, local, target));
    const result = applyDrag(request.status === 200, JSON.parse(request.responseText));
    groups[body.number].updateMatrixWorld(true);
    const after = groups[body.number].localToWorld(local.clone());
    status.drag = { moved: after.distanceTo(before), distance: result ? result.distance : null };
  }

  window.addEventListener("resize", resize);
  placeCamera();
  resize();
  if (animation) loadAnimation(animation);
  // `?speed=5`: one of the speeds of the list.
  const speed = document.getElementById("speed");
  if (Array.from(speed.options).some((o) => o.value === params.get("speed"))) speed.value = params.get("speed");
  if (params.get("play") === "1") setPlaying(true);
  // `?workspace=0`, `?boundary=1`, `?singular=0`: the workspace's layers shown or not.
  ["workspace", "boundary", "singular"].forEach((name) => {
    const box = document.getElementById("show-" + name);
    if (params.has(name) && box.checked !== (params.get(name) === "1")) box.click();
  });
  status.ready = true;
  report();
  if (params.get("drag-method")) document.getElementById("drag-method").value = params.get("drag-method");
  if (params.get("drag-test") === "1") {
    try { dragTest(); } catch (e) { status.error = String(e); }
  }
  setInterval(advance, 40);
  requestAnimationFrame(tick);
})();
