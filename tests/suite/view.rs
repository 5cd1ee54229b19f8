//! `lsdc view` and frame outputs: the scene's geometry against the closed loops, the standalone
//! page, the server over HTTP on 127.0.0.1, `simulate --output-frame` against the four-bar's
//! coupler curve in closed form, and (where Chromium is installed) the page in a real browser.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::PathBuf;

use lsdc::view::{page, server, Viewer};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::common::lsdc;
use crate::drag::coupler_point;

fn viewer(name: &str) -> Viewer {
    let mechanism = crate::common::programs::mechanism(name, &[]);
    let prepared = lsdc::prepare::prepare(&mechanism, &[], &Default::default())
        .unwrap_or_else(|_| panic!("{name} prepares"));
    Viewer::new(mechanism, prepared, name).expect("a scene")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lsdc-view-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A body's point in the fixed frame, from a pose `[x, y, z, qw, qx, qy, qz]`.
fn world(pose: &[f64; 7], local: &[f64; 3]) -> Vector3<f64> {
    let rotation =
        UnitQuaternion::from_quaternion(Quaternion::new(pose[3], pose[4], pose[5], pose[6]));
    Vector3::new(pose[0], pose[1], pose[2]) + rotation * Vector3::from(*local)
}

#[test]
fn the_four_bar_scene_has_its_joints_closed_and_its_loop_marked() {
    let viewer = viewer("four_bar");
    let scene = &viewer.scene;
    assert_eq!(scene.bodies.len(), 3);
    assert_eq!(scene.joints.len(), 4);
    let complementary: Vec<&str> = scene
        .joints
        .iter()
        .filter(|j| j.complementary)
        .map(|j| j.name.as_str())
        .collect();
    assert_eq!(complementary, ["c"]);
    assert!(scene
        .joints
        .iter()
        .all(|j| j.kind == "revolute" && j.axis == Some([0.0, 0.0, 1.0])));
    assert_eq!(scene.frames.len(), 1);
    assert_eq!(scene.frames[0].name, "coupler_point");
    // Each revolute's two frames meet: the first at `position` on its first body, the second
    // at one of the second body's points.
    let pose_of = |body: usize| {
        if body == 0 {
            [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
        } else {
            scene.poses[body - 1]
        }
    };
    for joint in &scene.joints {
        let at = world(&pose_of(joint.first_body), &joint.position);
        let second = &scene.bodies[joint.second_body - 1];
        let nearest = second
            .points
            .iter()
            .map(|p| (world(&pose_of(second.number), p) - at).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(nearest <= 1e-9, "{}: frames {nearest} apart", joint.name);
    }
    // A uniform bar of length l: the ellipsoid of its inertia has semi-axis √(5/12) l along it.
    let bar = &scene.bodies[0];
    let ellipsoid = bar.ellipsoid.expect("a massive body");
    let longest = ellipsoid.semi_axes.iter().copied().fold(0.0, f64::max);
    assert!(
        (longest - (5.0_f64 / 12.0).sqrt() * bar.mass).abs() <= 1e-3,
        "{longest}"
    );
}

#[test]
fn the_page_stands_alone() {
    let three = page::three_script().expect("the module's exports");
    assert!(three.contains("window.THREE={") && three.contains("WebGLRenderer:"));
    assert!(!three.contains("export{"));
    let mut viewer = viewer("four_bar");
    let animation = viewer.simulate(Some(0.5)).unwrap();
    assert!((animation.times.last().unwrap() - 0.5).abs() < 1e-12);
    viewer.results = Some(animation);
    let html = viewer.page(false);
    for external in ["<script src", "<link", "import(", "fetch(\"http"] {
        assert!(!html.contains(external), "the page loads `{external}`");
    }
    assert_eq!(
        html.matches("</script>").count(),
        html.matches("<script").count()
    );
    assert!(html.contains("\"coupler_point.x\""), "the frame's series");
}

#[test]
fn simulate_writes_the_frames_the_coupler_curve_predicts() {
    let (code, out, err) = lsdc(&[
        "simulate",
        "examples/four_bar.lsd",
        "--duration",
        "1",
        "--every",
        "0.1",
        "--output-frame",
        "coupler_point",
    ]);
    assert_eq!(code, 0, "{err}");
    let mut lines = out.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no {name}"))
    };
    let (crank, rate) = (column("crank.q"), column("crank.q'"));
    let (x, vx) = (column("coupler_point.x"), column("coupler_point.vx"));
    assert_eq!(header[header.len() - 1], "coupler_point.wz");
    let mut rows = 0;
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|f| f.parse().unwrap()).collect();
        let t = v[crank];
        let expected = coupler_point(t);
        assert!(
            (v[x] - expected[0]).abs() <= 1e-8 && (v[x + 1] - expected[1]).abs() <= 1e-8,
            "{line}"
        );
        let h = 1e-6;
        let (ahead, behind) = (coupler_point(t + h), coupler_point(t - h));
        for c in 0..2 {
            let velocity = (ahead[c] - behind[c]) / (2.0 * h) * v[rate];
            assert!(
                (v[vx + c] - velocity).abs() <= 1e-6 * (1.0 + velocity.abs()),
                "{line}"
            );
        }
        rows += 1;
    }
    assert_eq!(rows, 11);
}

#[test]
fn view_plays_recorded_results_of_the_same_mechanism_only() {
    let run = scratch("run.json");
    let page = scratch("page.html");
    let run_path = run.to_str().unwrap();
    let (code, _, err) = lsdc(&[
        "simulate",
        "examples/four_bar.lsd",
        "--duration",
        "0.3",
        "--format",
        "json",
        "-o",
        run_path,
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = lsdc(&[
        "view",
        "examples/four_bar.lsd",
        "--results",
        run_path,
        "--export",
        page.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("\"times\":[0.0,"), "the recorded times");
    let (code, _, err) = lsdc(&[
        "view",
        "examples/pendulum.lsd",
        "--results",
        run_path,
        "--export",
        page.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("are not this mechanism's"), "{err}");
}

/// One HTTP exchange: status line and body.
fn http(address: &str, request: &str) -> (String, String) {
    let mut stream = TcpStream::connect(address).unwrap();
    stream.write_all(request.as_bytes()).unwrap();
    let mut response = String::new();
    stream.read_to_string(&mut response).unwrap();
    let (head, body) = response.split_once("\r\n\r\n").unwrap();
    (head.lines().next().unwrap().to_string(), body.to_string())
}

fn post(path: &str, body: &str) -> String {
    format!("POST {path} HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}", body.len())
}

#[test]
fn the_server_answers_the_page_the_scene_runs_and_drags() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let shown = viewer("four_bar");
    let coordinates = shown.scene.coordinates.clone();
    let coupler = shown
        .scene
        .bodies
        .iter()
        .find(|b| b.name == "bar2")
        .unwrap()
        .number;
    // The mechanism's names are not shared between threads: the server builds its own.
    let requests = 7;
    let serving = std::thread::spawn(move || {
        server::serve(&listener, &mut viewer("four_bar"), Some(requests)).unwrap()
    });

    let (status, page) = http(&address, "GET / HTTP/1.1\r\nHost: x\r\n\r\n");
    assert_eq!(status, "HTTP/1.1 200 OK");
    assert!(page.contains("\"live\":true"));
    let (status, scene) = http(&address, "GET /api/scene HTTP/1.1\r\n\r\n");
    assert_eq!(status, "HTTP/1.1 200 OK");
    let scene: serde_json::Value = serde_json::from_str(&scene).unwrap();
    assert_eq!(scene["bodies"].as_array().unwrap().len(), 3);
    let (status, animation) = http(&address, "GET /api/simulate?duration=0.2 HTTP/1.1\r\n\r\n");
    assert_eq!(status, "HTTP/1.1 200 OK");
    let animation: serde_json::Value = serde_json::from_str(&animation).unwrap();
    assert_eq!(
        animation["times"]
            .as_array()
            .unwrap()
            .last()
            .unwrap()
            .as_f64(),
        Some(0.2)
    );
    let (status, _) = http(&address, "GET /api/simulate?duration=-1 HTTP/1.1\r\n\r\n");
    assert_eq!(status, "HTTP/1.1 400 Bad Request");

    // Drag the coupler's point (1.75, 1, 0) to where the coupler curve puts it at crank 1.1.
    let target = coupler_point(1.1);
    let request = serde_json::json!({ "body": coupler, "point": [1.75, 1.0, 0.0], "target": target, "coordinates": coordinates });
    let (status, moved) = http(&address, &post("/api/drag", &request.to_string()));
    assert_eq!(status, "HTTP/1.1 200 OK", "{moved}");
    let moved: serde_json::Value = serde_json::from_str(&moved).unwrap();
    assert!(
        moved["distance"].as_f64().unwrap() <= 1e-9 && moved["reached"] == true,
        "{moved}"
    );
    assert!(moved["loop_residual"].as_f64().unwrap() <= 1e-10);
    let (status, error) = http(&address, &post("/api/drag", "{\"body\": 9}"));
    assert_eq!(status, "HTTP/1.1 400 Bad Request");
    assert!(error.contains("not a drag request"), "{error}");
    let (status, _) = http(&address, "GET /elsewhere HTTP/1.1\r\n\r\n");
    assert_eq!(status, "HTTP/1.1 404 Not Found");
    serving.join().unwrap();
}

#[test]
fn view_prints_its_address_and_serves_there() {
    use std::io::BufRead;
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_lsdc"))
        .args(["view", "examples/pendulum.lsd", "--port", "0"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let address = line
        .strip_prefix("lsdc view: http://")
        .and_then(|rest| rest.split('/').next())
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .to_string();
    assert!(address.starts_with("127.0.0.1:"), "{address}");
    let (status, page) = http(&address, "GET / HTTP/1.1\r\n\r\n");
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(status, "HTTP/1.1 200 OK");
    assert!(page.contains("window.THREE="));
}

const CHROMIUM: &str = "/usr/bin/chromium";

/// Runs headless Chromium on `url` with `flags`; `None` (after saying so) when it is not
/// installed (`tools/install-chromium` installs it).
///
/// The page runs on virtual time: its timers and clock advance by `virtual_ms` whatever the
/// machine's load, and Chromium reads the page when they have. What remains of real time is
/// Chromium's own: its GPU watchdog, which kills a GPU process (here SwiftShader, in software)
/// that takes more than a few seconds over a frame, as it can on a loaded machine; it is off.
fn chromium(url: &str, virtual_ms: u32, flags: &[&str]) -> Option<std::process::Output> {
    if !std::path::Path::new(CHROMIUM).exists() {
        crate::common::skip(&format!(
            "no {CHROMIUM}, the page is not tested in a browser (tools/install-chromium installs it)"
        ));
        return None;
    }
    // A profile of its own: two instances sharing one hand their page over to the first.
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let profile = scratch(&format!("profile-{run}"));
    let output = std::process::Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--window-size=1000,700",
            "--disable-gpu-watchdog",
        ])
        .arg(format!("--virtual-time-budget={virtual_ms}"))
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(flags)
        .arg(url)
        .output()
        .expect("chromium runs");
    Some(output)
}

/// The page's `#status` after `virtual_ms` of its time. A browser that could not run the page
/// at all (no status written, or no WebGL context: the machine, not the page) is tried again,
/// up to three times in all, saying why; every assertion is on a page that ran.
fn page_status(url: &str, virtual_ms: u32) -> Option<serde_json::Value> {
    let mut why = String::new();
    for _ in 0..3 {
        let output = chromium(url, virtual_ms, &["--dump-dom"])?;
        let dom = String::from_utf8_lossy(&output.stdout);
        let status = status_in(&dom);
        let without_webgl = |s: &serde_json::Value| {
            s["error"]
                .as_str()
                .is_some_and(|e| e.starts_with("no WebGL"))
        };
        match status {
            Some(status) if !without_webgl(&status) => return Some(status),
            _ => {
                why = format!(
                    "{}; status {status:?}; {}",
                    output.status,
                    String::from_utf8_lossy(&output.stderr)
                );
                eprintln!("chromium did not run the page, again: {why}");
            }
        }
    }
    panic!("chromium did not run the page three times: {why}")
}

/// The JSON in a dumped page's `#status` element, if the page wrote it.
fn status_in(dom: &str) -> Option<serde_json::Value> {
    let tag = "<pre id=\"status\">";
    let start = dom.find(tag)? + tag.len();
    let end = start + dom[start..].find("</pre>")?;
    serde_json::from_str(&dom[start..end]).ok()
}

/// The pixels of a PNG, red, green and blue.
fn pixels(path: &std::path::Path) -> Vec<[u8; 3]> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buffer = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buffer).unwrap();
    let channels = info.color_type.samples();
    (buffer[..info.buffer_size()].chunks(channels))
        .map(|p| [p[0], p[1], p[2]])
        .collect()
}

/// Distinct colours of a PNG and the share of pixels unlike the top-left one.
fn picture(path: &std::path::Path) -> (usize, f64) {
    let pixels = pixels(path);
    let background = pixels[0];
    let colours: std::collections::HashSet<&[u8; 3]> = pixels.iter().collect();
    let different = pixels.iter().filter(|p| **p != background).count();
    (colours.len(), different as f64 / pixels.len() as f64)
}

#[test]
fn the_exported_delta_opens_offline_and_animates_in_chromium() {
    if !std::path::Path::new(CHROMIUM).exists() {
        crate::common::skip(&format!(
            "no {CHROMIUM}, the page is not tested in a browser (tools/install-chromium installs it)"
        ));
        return;
    }
    let page = scratch("delta.html");
    let (code, _, err) = lsdc(&[
        "view",
        "examples/delta_isir88.lsd",
        "--export",
        page.to_str().unwrap(),
        "--duration",
        "10",
    ]);
    assert_eq!(code, 0, "{err}");
    // Played 5 times faster, the 10 s run lasts 2 s of the page's time: 5 s see it through to
    // its last output and round again.
    let url = format!("file://{}?play=1&speed=5", page.display());
    let Some(status) = page_status(&url, 5000) else {
        return;
    };
    assert_eq!(status["error"], serde_json::Value::Null);
    assert_eq!(status["bodies"], 10);
    assert_eq!(status["complementary"], 5);
    assert!(status["objects"].as_u64().unwrap() > 30, "{status}");
    // The whole run: 10 s, outputs every 0.05 s, no failure; all of it played.
    assert_eq!(status["failure"], serde_json::Value::Null);
    assert_eq!(status["end"], 10.0, "{status}");
    assert_eq!(status["last"], 200, "{status}");
    assert!(
        status["advanced"] == true
            && status["furthest"] == status["last"]
            && status["laps"].as_u64().unwrap() >= 1,
        "{status}"
    );
    let shot = scratch("delta.png");
    chromium(&url, 5000, &[&format!("--screenshot={}", shot.display())]);
    let (colours, drawn) = picture(&shot);
    assert!(
        colours > 50 && drawn > 0.05,
        "{colours} colours, {drawn} drawn"
    );
}

#[test]
fn a_body_dragged_in_chromium_moves() {
    if !std::path::Path::new(CHROMIUM).exists() {
        crate::common::skip(&format!(
            "no {CHROMIUM}, the page is not tested in a browser (tools/install-chromium installs it)"
        ));
        return;
    }
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    // The browser opens connections of its own accord (an icon, ahead of need): the server
    // answers until the test process ends.
    std::thread::spawn(move || server::serve(&listener, &mut viewer("four_bar"), None));
    for method in ["exact", "penalty"] {
        let url = format!("http://{address}/?drag-test=1&drag-method={method}");
        let Some(status) = page_status(&url, 4000) else {
            return;
        };
        let moved = status["drag"]["moved"].as_f64().unwrap_or(0.0);
        assert!(
            moved > 1e-3 && status["drag"]["distance"].is_f64(),
            "{method}: {status}"
        );
    }
}

#[test]
fn the_page_drags_by_the_penalty_method_too() {
    use lsdc::view::{DragMethod, DragRequest};
    let shown = viewer("four_bar");
    let coupler = (shown.scene.bodies.iter())
        .find(|b| b.name == "bar2")
        .unwrap()
        .number;
    let target = coupler_point(1.1);
    let mut request = DragRequest {
        body: coupler,
        point: [1.75, 1.0, 0.0],
        target,
        coordinates: shown.scene.coordinates.clone(),
        method: DragMethod::Exact,
        planar: None,
    };
    let exact = shown.drag(&request).unwrap();
    // Moves towards the same target, each one linearised solve from the state the last left:
    // the penalty method converges to the configuration of the exact one.
    request.method = DragMethod::Penalty;
    let mut moved = shown.drag(&request).unwrap();
    let first_distance = moved.distance;
    for _ in 0..20 {
        request.planar = moved.planar.clone();
        moved = shown.drag(&request).unwrap();
    }
    assert!(
        first_distance > 1e-6 && moved.distance < 1e-6,
        "{first_distance} then {}",
        moved.distance
    );
    assert!(moved.loop_residual < 1e-5, "gap {}", moved.loop_residual);
    for (penalty, exact) in moved.poses.iter().zip(&exact.poses) {
        let local = [1.0, 0.0, 0.0];
        assert!((world(penalty, &local) - world(exact, &local)).norm() < 1e-5);
    }
    assert_eq!(moved.coordinates, request.coordinates);
}

#[test]
fn a_title_cannot_end_the_pages_script_or_fill_its_placeholders() {
    let title = "a<!--<script>b</script>&\u{2028}{{three}}";
    let mechanism = crate::common::programs::mechanism("four_bar", &[]);
    let prepared = lsdc::prepare::prepare(&mechanism, &[], &Default::default()).unwrap();
    let html = Viewer::new(mechanism, prepared, title).unwrap().page(false);
    let plain = viewer("four_bar").page(false);
    assert!(!html.contains("<!--"), "the title opens a comment");
    assert_eq!(
        html.matches("<script").count(),
        plain.matches("<script").count()
    );
    assert_eq!(html.matches("window.THREE={").count(), 1);
    let tag = "<script type=\"application/json\" id=\"scene-data\">";
    let start = html.find(tag).unwrap() + tag.len();
    let end = start + html[start..].find("</script>").unwrap();
    let scene: serde_json::Value = serde_json::from_str(&html[start..end]).unwrap();
    assert_eq!(scene["title"], title);
}

/// A served viewer of the four-bar that answers `requests` requests, and its address.
fn serving(requests: usize) -> (String, std::thread::JoinHandle<()>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let handle = std::thread::spawn(move || {
        server::serve(&listener, &mut viewer("four_bar"), Some(requests)).unwrap()
    });
    (address, handle)
}

#[test]
fn idle_connections_hold_up_no_request() {
    let (address, server) = serving(2);
    // The page's first request, so that building the viewer is not timed.
    let (status, _) = http(&address, "GET /api/scene HTTP/1.1\r\n\r\n");
    assert_eq!(status, "HTTP/1.1 200 OK");
    let idle: Vec<TcpStream> = (0..100)
        .map(|_| TcpStream::connect(&address).unwrap())
        .collect();
    let (status, _) = http(&address, "GET /api/scene HTTP/1.1\r\n\r\n");
    assert_eq!(status, "HTTP/1.1 200 OK");
    // Served one at a time, the request would be answered only after the server had given up
    // on each idle connection and closed it; answered beside them, every idle connection is
    // still open (nothing to read yet, rather than the end of the stream). An order of events,
    // not a duration.
    for (n, connection) in idle.iter().enumerate() {
        connection.set_nonblocking(true).unwrap();
        let peeked = connection.peek(&mut [0u8; 1]);
        assert!(
            matches!(&peeked, Err(e) if e.kind() == std::io::ErrorKind::WouldBlock),
            "idle connection {n} was closed or answered before the request: {peeked:?}"
        );
    }
    drop(idle);
    server.join().unwrap();
}

#[test]
fn a_served_simulation_is_bounded() {
    let (address, server) = serving(2);
    let (status, error) = http(
        &address,
        "GET /api/simulate?duration=499999 HTTP/1.1\r\n\r\n",
    );
    assert_eq!(status, "HTTP/1.1 400 Bad Request", "{error}");
    assert!(
        error.contains("frames") && error.contains("--results"),
        "{error}"
    );
    // Within the frames, the steps are bounded: the run stops with its failure said.
    let (status, animation) = http(&address, "GET /api/simulate?duration=4000 HTTP/1.1\r\n\r\n");
    assert_eq!(status, "HTTP/1.1 200 OK");
    let animation: serde_json::Value = serde_json::from_str(&animation).unwrap();
    let failure = animation["failure"].as_str().unwrap_or_default();
    assert!(
        failure.contains(&format!("{} steps", server::MAX_STEPS)),
        "{failure}"
    );
    server.join().unwrap();
}

/// The page of the pendulum's run at `tolerance`, and the plot it drew in Chromium (`None`
/// where Chromium is missing, after saying so).
fn plotted(tolerance: &str) -> Option<Vec<serde_json::Value>> {
    if !std::path::Path::new(CHROMIUM).exists() {
        crate::common::skip(&format!(
            "no {CHROMIUM}, the page is not tested in a browser (tools/install-chromium installs it)"
        ));
        return None;
    }
    let run = scratch(&format!("pendulum-{tolerance}.json"));
    let page = scratch(&format!("pendulum-{tolerance}.html"));
    let (code, _, err) = lsdc(&[
        "simulate",
        "examples/pendulum.lsd",
        "--tolerance",
        tolerance,
        "--format",
        "json",
        "-o",
        run.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = lsdc(&[
        "view",
        "examples/pendulum.lsd",
        "--results",
        run.to_str().unwrap(),
        "--export",
        page.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let status = page_status(&format!("file://{}", page.display()), 1000)?;
    Some(status["plot"].as_array().expect("the plot drawn").clone())
}

#[test]
fn a_conserved_energy_is_plotted_flat_with_its_value() {
    // The pendulum's energy, −m g l cos 60° = −2.943 J, kept to 1e-11 or so at tolerance 1e-12.
    let Some(plot) = plotted("1e-12") else {
        return;
    };
    let energy = plot.iter().find(|s| s["name"] == "energy").expect("energy");
    assert_eq!(energy["flat"], true, "{energy}");
    let value: f64 = energy["low"].as_str().unwrap().parse().unwrap();
    assert!((value + 2.943).abs() < 1e-8, "{energy}");
    // The swing angle varies: its axis spans its range.
    assert!(
        plot.iter()
            .any(|s| s["name"] == "swing.q" && s["flat"] == false),
        "{plot:?}"
    );
    // At tolerance 1e-7 the energy drifts by 7e-7 of itself: shown, its ends told apart.
    let Some(plot) = plotted("1e-7") else {
        return;
    };
    let energy = plot.iter().find(|s| s["name"] == "energy").expect("energy");
    assert_eq!(energy["flat"], false, "{energy}");
    assert_ne!(energy["low"], energy["high"], "{energy}");
}

/// A rheonomic joint in the viewer: the bead on the spinning rod moves on its closed form,
/// r0 cosh(w t) along the rod turned by w t, and the torque that turns the rod is one of the
/// page's series.
#[test]
fn the_viewer_moves_a_rheonomic_joint_and_plots_its_effort() {
    let mut viewer = viewer("bead_on_spinning_rod");
    let animation = viewer.simulate(Some(1.0)).expect("a run");
    let (w, r0) = (3.0, 0.1);
    for (t, poses) in animation.times.iter().zip(&animation.poses) {
        let (r, angle) = (r0 * (w * t).cosh(), w * t);
        let bead = world(&poses[0], &[0.0, 0.0, 0.0]);
        let expected = Vector3::new(r * angle.cos(), r * angle.sin(), 0.0);
        assert!((bead - expected).norm() < 1e-8 * r, "t = {t}: {bead:?}");
    }
    let torque = (animation.series.iter())
        .find(|s| s.name == "rod.motion1_effort")
        .expect("the effort's series");
    assert_eq!(torque.values.len(), animation.times.len());
    assert!(torque.values.last().is_some_and(|&v| v > 9.0));
}

/// The Delta's workspace over the arms' box [0.6, 1.2]³ rad, `cells` per arm, in an exported
/// page: the page, and `lsdc workspace --format json` on the same sampling.
fn delta_workspace_page(cells: &str) -> (PathBuf, serde_json::Value) {
    let sampling = [
        "--actuate",
        "A1.q",
        "--actuate",
        "A2.q",
        "--actuate",
        "A3.q",
        "--range",
        "A1.q=0.6:1.2",
        "--range",
        "A2.q=0.6:1.2",
        "--range",
        "A3.q=0.6:1.2",
        "--samples",
        cells,
    ];
    let page = scratch(&format!("delta-workspace-{cells}.html"));
    let mut view = vec![
        "view",
        "examples/delta_isir88.lsd",
        "--workspace",
        "nacelle",
    ];
    view.extend(sampling);
    view.extend(["--duration", "0.1", "--export", page.to_str().unwrap()]);
    let (code, _, err) = lsdc(&view);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("workspace of `nacelle`: volume"), "{err}");
    let mut workspace = vec![
        "workspace",
        "examples/delta_isir88.lsd",
        "--point",
        "nacelle",
    ];
    workspace.extend(sampling);
    workspace.extend(["--format", "json"]);
    let (code, out, err) = lsdc(&workspace);
    assert_eq!(code, 0, "{err}");
    (page, serde_json::from_str(&out).unwrap())
}

/// The scene's JSON in an exported page.
fn scene_of(page: &std::path::Path) -> serde_json::Value {
    let html = std::fs::read_to_string(page).unwrap();
    let tag = "<script type=\"application/json\" id=\"scene-data\">";
    let start = html.find(tag).unwrap() + tag.len();
    let end = start + html[start..].find("</script>").unwrap();
    serde_json::from_str(&html[start..end]).unwrap()
}

/// The workspace layer of `lsdc view --workspace` holds what `lsdc workspace` samples: every
/// reachable point in the same order, the boundary samples, and the colours of the dexterity's
/// scale (the best conditioned yellow, the worst purple, as the slices draw them).
#[test]
fn the_workspace_layer_is_the_sampled_workspace_coloured_by_dexterity() {
    let (page, sampled) = delta_workspace_page("4");
    let layer = &scene_of(&page)["workspace"];
    let samples = sampled["samples"].as_array().unwrap();
    let reachable: Vec<&serde_json::Value> = (samples.iter())
        .filter(|s| s["reachable"] == true)
        .collect();
    let points = layer["points"].as_array().unwrap();
    assert_eq!(points.len(), 64);
    assert_eq!(points.len(), reachable.len());
    for (point, sample) in points.iter().zip(&reachable) {
        assert_eq!(point, &sample["point"], "{sample}");
    }
    let boundary: Vec<u64> = (reachable.iter().enumerate())
        .filter(|(_, s)| s["boundary"] == true)
        .map(|(k, _)| k as u64)
        .collect();
    let layer_boundary: Vec<u64> = (layer["boundary"].as_array().unwrap().iter())
        .map(|k| k.as_u64().unwrap())
        .collect();
    // The 4³ grid's 56 samples on the box's faces (every arm angle assembles).
    assert_eq!(layer_boundary, boundary);
    assert_eq!(boundary.len(), 56);
    let dexterity: Vec<f64> = (reachable.iter())
        .map(|s| s["dexterity"].as_f64().unwrap())
        .collect();
    let colour = |k: usize| -> Vec<u64> {
        (layer["colours"][k].as_array().unwrap().iter())
            .map(|c| c.as_u64().unwrap())
            .collect()
    };
    let best = (0..dexterity.len())
        .min_by(|&a, &b| dexterity[a].total_cmp(&dexterity[b]))
        .unwrap();
    let worst = (0..dexterity.len())
        .max_by(|&a, &b| dexterity[a].total_cmp(&dexterity[b]))
        .unwrap();
    assert_eq!(colour(best), [253, 231, 37]);
    assert_eq!(colour(worst), [68, 1, 84]);
    let range = layer["dexterity"].as_array().unwrap();
    assert!((range[0].as_f64().unwrap() / dexterity[best] - 1.0).abs() < 1e-12);
    assert!((range[1].as_f64().unwrap() / dexterity[worst] - 1.0).abs() < 1e-12);
    assert!(layer["singular"].as_array().unwrap().is_empty());
    // The sampling's options belong to the workspace.
    let (code, _, err) = lsdc(&["view", "examples/delta_isir88.lsd", "--actuate", "A1.q"]);
    assert_eq!(code, 2);
    assert!(err.contains("give `--workspace FRAME`"), "{err}");
}

/// In a browser the layer is drawn: its dots, in the colours of the scale, cover pixels of the
/// picture that the page with the layer unticked (`?workspace=0`) does not have.
#[test]
fn the_workspace_layer_is_drawn_and_toggled_in_chromium() {
    if !std::path::Path::new(CHROMIUM).exists() {
        crate::common::skip(&format!(
            "no {CHROMIUM}, the page is not tested in a browser (tools/install-chromium installs it)"
        ));
        return;
    }
    let (page, _) = delta_workspace_page("8");
    let layer = &scene_of(&page)["workspace"];
    let colours: Vec<[u8; 3]> = (layer["colours"].as_array().unwrap().iter())
        .map(|c| std::array::from_fn(|k| c[k].as_u64().unwrap() as u8))
        .collect();
    let url = |query: &str| format!("file://{}?{query}", page.display());
    let mut counts = Vec::new();
    for (query, shown) in [("workspace=1", true), ("workspace=0", false)] {
        let Some(status) = page_status(&url(query), 1000) else {
            return;
        };
        assert_eq!(status["error"], serde_json::Value::Null);
        let workspace = &status["workspace"];
        assert_eq!(workspace["points"], 512, "{status}");
        assert_eq!(workspace["workspace_shown"], shown, "{status}");
        assert_eq!(workspace["boundary_shown"], false, "{status}");
        let shot = scratch(&format!("delta-workspace-{shown}.png"));
        chromium(
            &url(query),
            1000,
            &[&format!("--screenshot={}", shot.display())],
        );
        // Pixels within 2 of a colour of the layer in each channel (the page's sRGB output
        // rounds the dots' colours back to themselves, or next to them).
        let near = |p: &[u8; 3]| {
            colours
                .iter()
                .any(|c| (0..3).all(|k| p[k].abs_diff(c[k]) <= 2))
        };
        counts.push(pixels(&shot).iter().filter(|p| near(p)).count());
    }
    assert!(
        counts[0] > 2000 && counts[0] > 10 * counts[1].max(1),
        "pixels in the layer's colours, shown and hidden: {counts:?}"
    );
}
