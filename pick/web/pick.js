// roadside pick: the page. Plain JavaScript and Leaflet (window.L: from npm at build time, served
// by roadside itself, pick/web/package.json); no network beyond its own server and the web tile
// host the user named (--tiles; the page's Content-Security-Policy allows that one).
// Two views: the camera image on a canvas (pixel (0,0) is the centre of the top-left pixel,
// docs/conventions.md) and the site from above, a Leaflet map (site ENU metres, east right, north
// up). Every change is a POST to the server, which re-solves and answers with the whole state.
"use strict";
(function () {
  const $ = (id) => document.getElementById(id);
  const st = { state: null, map: null, selected: null, pendingPx: null, pendingEn: null, ground: true,
               image: null, ready: false, tilesLoaded: [], webTiles: new Map(), drag: null };
  let ARROW_GAIN = 20; // residual arrows magnified: 20x, less when the largest would leave the view

  // ---- a zoomable, pannable view: canvas = offset + scale * world (y flipped for the map) ----
  function View(canvas, flipY) {
    this.c = canvas; this.flip = flipY; this.s = 1; this.ox = 0; this.oy = 0;
  }
  View.prototype.toCanvas = function (x, y) {
    return [this.ox + this.s * x, this.flip ? this.oy - this.s * y : this.oy + this.s * y];
  };
  View.prototype.toWorld = function (cx, cy) {
    return [(cx - this.ox) / this.s, this.flip ? (this.oy - cy) / this.s : (cy - this.oy) / this.s];
  };
  View.prototype.fit = function (x0, y0, x1, y1) { // world box into the canvas
    const w = this.c.width, h = this.c.height;
    this.s = Math.min(w / Math.max(x1 - x0, 1e-9), h / Math.max(y1 - y0, 1e-9)) * 0.95;
    const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
    this.ox = w / 2 - this.s * cx;
    this.oy = this.flip ? h / 2 + this.s * cy : h / 2 - this.s * cy;
  };
  View.prototype.zoom = function (cx, cy, f) {
    this.ox = cx - (cx - this.ox) * f; this.oy = cy - (cy - this.oy) * f; this.s *= f;
  };

  const img = new View($("image"), false);

  // image-continuous X (pixel i covers [i, i+1)) <-> pixel u = X - 0.5
  const pxToWorld = (u, v) => [u + 0.5, v + 0.5];
  const worldToPx = (X, Y) => [X - 0.5, Y - 0.5];

  function camSize() {
    const c = st.state.camera;
    return [c.width || (st.image ? st.image.width : 1920), c.height || (st.image ? st.image.height : 1080)];
  }

  function fitImage() { const [w, h] = camSize(); img.fit(0, 0, w, h); }

  // ---- the server ----
  async function getJSON(url) { const r = await fetch(url); if (!r.ok) throw new Error(url + ": " + r.status); return r.json(); }
  async function rgbCanvas(url, w, h) {
    const r = await fetch(url);
    if (!r.ok) return null;
    const rgb = new Uint8Array(await r.arrayBuffer());
    if (rgb.length !== w * h * 3) return null;
    const cv = document.createElement("canvas"); cv.width = w; cv.height = h;
    const ctx = cv.getContext("2d"), id = ctx.createImageData(w, h);
    for (let i = 0, j = 0; i < rgb.length; i += 3, j += 4) {
      id.data[j] = rgb[i]; id.data[j + 1] = rgb[i + 1]; id.data[j + 2] = rgb[i + 2]; id.data[j + 3] = 255;
    }
    ctx.putImageData(id, 0, 0);
    return cv;
  }
  async function post(url, body) {
    status("…");
    const r = await fetch(url, { method: "POST", headers: { "Content-Type": "application/json" },
                                 body: JSON.stringify(body || {}) });
    const j = await r.json();
    if (!r.ok) { status(j.error || ("error " + r.status), true); return false; }
    st.state = j; st.pendingPx = null; st.pendingEn = null;
    status(j.solve.ok ? `solved in ${j.solve.time_ms.toFixed(1)} ms` : j.solve.message);
    render();
    return true;
  }
  function status(text, bad) { const s = $("status"); s.textContent = text; s.style.color = bad ? "#ff8a80" : ""; }

  // ---- drawing ----
  function size(canvas) {
    if (canvas.width !== canvas.clientWidth || canvas.height !== canvas.clientHeight) {
      canvas.width = canvas.clientWidth; canvas.height = canvas.clientHeight; return true;
    }
    return false;
  }
  function dot(ctx, x, y, r, fill, stroke) {
    ctx.beginPath(); ctx.arc(x, y, r, 0, 2 * Math.PI);
    if (fill) { ctx.fillStyle = fill; ctx.fill(); }
    if (stroke) { ctx.strokeStyle = stroke; ctx.lineWidth = 1.5; ctx.stroke(); }
  }
  function label(ctx, x, y, text, color) {
    ctx.font = "11px sans-serif"; ctx.lineWidth = 3; ctx.strokeStyle = "rgba(0,0,0,0.7)";
    ctx.strokeText(text, x, y); ctx.fillStyle = color; ctx.fillText(text, x, y);
  }
  const colorOf = (l) => l.flagged ? "#ff1744" : (l.pick_px ? "#00e676" : "#40c4ff");

  function drawImage() {
    const c = img.c, ctx = c.getContext("2d"), S = st.state;
    ctx.setTransform(1, 0, 0, 1, 0, 0); ctx.clearRect(0, 0, c.width, c.height);
    const [w, h] = camSize();
    const [x0, y0] = img.toCanvas(0, 0);
    const rmax = Math.max(1e-9, ...S.landmarks.filter((l) => l.residual_px).map((l) => l.residual_norm_px));
    ARROW_GAIN = Math.max(1, Math.min(20, Math.floor(0.05 * w / rmax)));
    ctx.imageSmoothingEnabled = img.s < 2;
    if (st.image) ctx.drawImage(st.image, x0, y0, w * img.s, h * img.s);
    else { ctx.fillStyle = "#9e9e9e"; ctx.fillRect(x0, y0, w * img.s, h * img.s); }
    if (st.ground && S.ground_uncertainty) drawHeat(ctx, S.ground_uncertainty, w, h);
    for (const l of S.landmarks) {
      const sel = st.selected === l.id;
      const pp = l.predicted_px;
      if (pp && pp[0] !== null && pp[0] > -w && pp[0] < 2 * w && pp[1] > -h && pp[1] < 2 * h) { // every landmark's predicted pixel
        const [px, py] = img.toCanvas(...pxToWorld(l.predicted_px[0], l.predicted_px[1]));
        dot(ctx, px, py, sel ? 9 : 5, null, sel ? "#ffff00" : "#40c4ff");
        if (!l.pick_px) label(ctx, px + 7, py - 5, l.id, "#b3e5fc");
      }
      if (!l.pick_px) continue;
      const dragged = st.drag && st.drag.view === img && st.drag.id === l.id;
      const [qx, qy] = dragged ? img.toCanvas(...st.drag.at) : img.toCanvas(...pxToWorld(l.pick_px[0], l.pick_px[1]));
      const col = colorOf(l);
      ctx.strokeStyle = col; ctx.lineWidth = 2;
      ctx.beginPath(); ctx.moveTo(qx - 6, qy); ctx.lineTo(qx + 6, qy); ctx.moveTo(qx, qy - 6); ctx.lineTo(qx, qy + 6); ctx.stroke();
      if (sel) dot(ctx, qx, qy, 10, null, "#ffff00");
      if (l.residual_px) { // the residual arrow, pick -> predicted, magnified
        const ex = qx + ARROW_GAIN * img.s * l.residual_px[0], ey = qy + ARROW_GAIN * img.s * l.residual_px[1];
        ctx.beginPath(); ctx.moveTo(qx, qy); ctx.lineTo(ex, ey); ctx.stroke();
        const a = Math.atan2(ey - qy, ex - qx);
        ctx.beginPath(); ctx.moveTo(ex, ey); ctx.lineTo(ex - 7 * Math.cos(a - 0.4), ey - 7 * Math.sin(a - 0.4));
        ctx.lineTo(ex - 7 * Math.cos(a + 0.4), ey - 7 * Math.sin(a + 0.4)); ctx.closePath(); ctx.fillStyle = col; ctx.fill();
        label(ctx, qx + 8, qy + 14, `${l.id} ${l.residual_norm_px.toFixed(2)} px`, col);
      } else label(ctx, qx + 8, qy + 14, l.id, col);
    }
    if (st.pendingPx) {
      const [x, y] = img.toCanvas(...pxToWorld(st.pendingPx[0], st.pendingPx[1]));
      dot(ctx, x, y, 7, null, "#ff00ff");
    }
    label(ctx, 6, c.height - 8, `residual arrows x${ARROW_GAIN}`, "#fff");
  }

  // ---- the site from above: a Leaflet map on the site's ENU metres (L.CRS.Simple: lat = N,
  // lng = E). With an orthophoto its grid sets the CRS: at Leaflet zoom 0 one screen pixel is one
  // source cell (level 0, full resolution), zoom -L is level L, and the tile grid starts at the
  // raster's north-west corner, so Leaflet's tile (z, x, y) is the server's /api/tiles/-z/x/y.
  let lmap = null, A = 1; // A: screen pixels per metre at zoom 0
  const ll = (e, n) => L.latLng(n, e);
  const enOf = (p) => [p.lng, p.lat];
  const mapScale = () => A * Math.pow(2, lmap.getZoom()); // screen pixels per metre
  let layers = null; // the markers and drawings redrawn on each state

  function createMap() {
    const o = st.map.ortho;
    let b = 0, d = 0, ex = 0, ny = 0;
    if (o) { A = 1 / o.cell_m; ex = o.e0_m - o.cell_m / 2; ny = o.n0_m + o.cell_m / 2; b = -A * ex; d = A * ny; }
    const crs = L.extend({}, L.CRS.Simple, { transformation: new L.Transformation(A, b, -A, d) });
    const zmin = Math.log2(0.05 / A), zmax = Math.log2(Math.max(512, 8 * A) / A); // 0.05 px/m .. 8x the cells
    lmap = L.map("map", { crs, zoomSnap: 0, minZoom: zmin, maxZoom: zmax, scrollWheelZoom: false, doubleClickZoom: false,
                          boxZoom: false, keyboard: false, zoomAnimation: false, fadeAnimation: false,
                          markerZoomAnimation: false, inertia: false, attributionControl: false });
    lmap.setView([0, 0], 0);
    const c = lmap.getContainer();
    c.addEventListener("wheel", (e) => { // the page's zoom step (1.25x a notch), at once, around the pointer
      e.preventDefault();
      const z = Math.max(zmin, Math.min(zmax, lmap.getZoom() + Math.log2(e.deltaY < 0 ? 1.25 : 0.8)));
      lmap.setZoomAround(lmap.mouseEventToContainerPoint(e), z, { animate: false });
    }, { passive: false });
    if (st.map.tiles) { lmap.createPane("web").style.zIndex = 150; new WebTiles().addTo(lmap); } // under the orthophoto
    if (o) {
      const T = o.tile_px;
      const Ortho = L.GridLayer.extend({
        createTile(t, done) { // level -t.z's RGBA tile from the server, onto a canvas
          const cv = L.DomUtil.create("canvas"), key = `${-t.z}/${t.x}/${t.y}`;
          cv.width = T; cv.height = T;
          fetch("/api/tiles/" + key).then((r) => r.ok ? r.arrayBuffer() : null).then((buf) => {
            if (buf && buf.byteLength === T * T * 4) {
              cv.getContext("2d").putImageData(new ImageData(new Uint8ClampedArray(buf), T, T), 0, 0);
              st.tilesLoaded.push(key);
            }
            done(null, cv);
          }).catch((err) => done(err, cv));
          return cv;
        },
      });
      const bounds = L.latLngBounds(ll(ex, ny - o.height * o.cell_m), ll(ex + o.width * o.cell_m, ny));
      new Ortho({ tileSize: T, bounds, minZoom: zmin, maxZoom: zmax, minNativeZoom: -(o.levels - 1), maxNativeZoom: 0,
                  updateWhenZooming: false }).addTo(lmap);
    }
    layers = L.layerGroup().addTo(lmap);
    lmap.on("zoomend", onZoom);
    lmap.on("click", (ev) => { const [e, n] = enOf(ev.latlng); mapClick(e, n, nearestLandmark(e, n, 10)); });
    lmap.on("mousemove", (ev) => readoutMap(...enOf(ev.latlng)));
    // a map pick is dropped where the pointer is released (the marker's own position is whole pixels)
    // (a pointerup: Leaflet's drag cancels the pointerdown, and with it the mouse events that follow)
    document.addEventListener("pointerup", (ev) => { st.lastUp = ev; }, true);
  }

  function onZoom() {
    const o = st.map.ortho;
    if (o) { // the level Leaflet's GridLayer reads (its tile zoom: the map's zoom rounded); cells as squares from 2x
      st.orthoLevel = Math.max(0, Math.min(o.levels - 1, -Math.round(lmap.getZoom())));
      lmap.getContainer().classList.toggle("pixels", mapScale() * o.cell_m >= 2);
    }
    drawMap();
  }

  function fitMap() {
    let b = [Infinity, Infinity, -Infinity, -Infinity];
    const grow = (e, n) => { b = [Math.min(b[0], e), Math.min(b[1], n), Math.max(b[2], e), Math.max(b[3], n)]; };
    for (const l of st.state.landmarks) grow(l.enu_m[0], l.enu_m[1]);
    for (const l of st.map.lanes) for (const p of l.en_m) grow(p[0], p[1]);
    if (st.state.solve.ok) grow(st.state.solve.position_enu_m[0], st.state.solve.position_enu_m[1]);
    if (!isFinite(b[0])) b = [-50, -50, 50, 50];
    lmap.fitBounds(L.latLngBounds(ll(b[0] - 5, b[1] - 5), ll(b[2] + 5, b[3] + 5)), { animate: false, padding: [10, 10] });
  }

  const colorClass = (l) => l.flagged ? "flagged" : (l.pick_px ? "picked" : "open");
  const textIcon = (text, cls) => L.divIcon({ className: "rs-text " + cls, html: esc(text), iconSize: [0, 0] });
  function drawMap() {
    const S = st.state, s = mapScale();
    layers.clearLayers();
    if (!st.map.ortho && !st.map.tiles) { // a plain drawing of the lanes
      for (const l of st.map.lanes)
        L.polyline(l.en_m.map((p) => ll(p[0], p[1])), { color: l.junction ? "#b0bec5" : "#78909c", weight: Math.max(1, l.width_m * s),
                                                        lineCap: "round", interactive: false }).addTo(layers);
    }
    if (S.solve.ok) { // the camera: position, heading, 2-sigma ellipse of its E-N position
      const p = S.solve.position_enu_m, yaw = S.solve.yaw_pitch_roll_deg[0] * Math.PI / 180;
      const C = S.solve.covariance_position_en_m2, a = C[0], b = C[1], d = C[3];
      const tr = (a + d) / 2, disc = Math.sqrt(Math.max(0, (a - d) * (a - d) / 4 + b * b));
      const l1 = tr + disc, l2 = Math.max(0, tr - disc), ang = 0.5 * Math.atan2(2 * b, a - d); // major axis from east, anticlockwise
      const r1 = 2 * Math.sqrt(l1), r2 = 2 * Math.sqrt(l2), R1 = Math.max(r1, 1 / s), R2 = Math.max(r2, 1 / s);
      const ring = [];
      for (let k = 0; k < 64; k++) {
        const t = 2 * Math.PI * k / 64, x = R1 * Math.cos(t), y = R2 * Math.sin(t);
        ring.push(ll(p[0] + x * Math.cos(ang) - y * Math.sin(ang), p[1] + x * Math.sin(ang) + y * Math.cos(ang)));
      }
      const cam = { color: "#ff6d00", interactive: false };
      L.polygon(ring, { ...cam, weight: 2, fill: false }).addTo(layers);
      L.polyline([ll(p[0], p[1]), ll(p[0] + 30 / s * Math.sin(yaw), p[1] + 30 / s * Math.cos(yaw))], { ...cam, weight: 3 }).addTo(layers);
      L.circleMarker(ll(p[0], p[1]), { ...cam, radius: 6, color: "#000", weight: 1.5, fillColor: "#ff6d00", fillOpacity: 1 }).addTo(layers);
      L.marker(ll(p[0], p[1]), { icon: textIcon(`camera, 2σ ${r1.toFixed(2)} × ${r2.toFixed(2)} m`, "camera"), interactive: false }).addTo(layers);
    }
    for (const l of S.landmarks) { // draggable when a map pick; a surveyed landmark stays where the survey put it
      const movable = l.kind === "map-pick";
      const icon = L.divIcon({ className: `rs-landmark ${colorClass(l)}${st.selected === l.id ? " selected" : ""}`,
                               html: `<span class="label">${esc(l.id)}</span>`, iconSize: [10, 10] });
      const m = L.marker(ll(l.enu_m[0], l.enu_m[1]), { icon, draggable: movable, keyboard: false }).addTo(layers);
      m.on("click", (ev) => { // the landmark nearest the pointer: icons of landmarks a few pixels apart overlap
        const [e, n] = enOf(lmap.mouseEventToLatLng(ev.originalEvent));
        mapClick(e, n, nearestLandmark(e, n, 10) || l);
      });
      if (movable) m.on("dragend", () => {
        const [e, n] = enOf(st.lastUp ? lmap.mouseEventToLatLng(st.lastUp) : m.getLatLng());
        post("/api/landmark/move", { landmark: l.id, e, n });
      });
      else m.on("mousedown", () => status(`${l.id} is surveyed: it stays where the survey put it (only map picks move)`));
    }
    if (st.pendingEn) L.circleMarker(ll(...st.pendingEn), { radius: 7, color: "#ff00ff", weight: 1.5, fill: false, interactive: false }).addTo(layers);
  }

  // web tiles (--tiles): web mercator z/x/y drawn onto the site's ENU by the local linearisation,
  // on a canvas over the map's view (a Leaflet layer in a pane under the orthophoto's)
  const lonLatToEn = (lon, lat) => {
    const g = st.map.geo, J = g.den_dlonlat, dl = lon - g.lon0, dp = lat - g.lat0;
    return [J[0] * dl + J[1] * dp, J[2] * dl + J[3] * dp];
  };
  const enToLonLat = (e, n) => {
    const g = st.map.geo, J = g.den_dlonlat, det = J[0] * J[3] - J[1] * J[2];
    return [g.lon0 + (J[3] * e - J[1] * n) / det, g.lat0 + (-J[2] * e + J[0] * n) / det];
  };
  const tileLonLat = (z, x, y) => { // the north-west corner of web mercator tile (z, x, y)
    const k = Math.pow(2, z);
    return [x / k * 360 - 180, Math.atan(Math.sinh(Math.PI * (1 - 2 * y / k))) * 180 / Math.PI];
  };
  const WebTiles = L.Layer.extend({
    onAdd(m) {
      this.cv = L.DomUtil.create("canvas", "leaflet-layer rs-web-tiles", m.getPane("web"));
      m.on("move zoom viewreset resize", this.draw, this);
      this.draw();
    },
    onRemove(m) { L.DomUtil.remove(this.cv); m.off("move zoom viewreset resize", this.draw, this); },
    draw() {
      const t = st.map.tiles, m = this._map, size = m.getSize(), cv = this.cv, lat0 = st.map.geo.lat0 * Math.PI / 180;
      cv.width = size.x; cv.height = size.y;
      L.DomUtil.setPosition(cv, m.containerPointToLayerPoint([0, 0]));
      const ctx = cv.getContext("2d");
      const z = Math.max(0, Math.min(t.max_zoom, Math.round(Math.log2(156543.03392 * Math.cos(lat0) * mapScale() / 1.0))));
      const k = Math.pow(2, z);
      const corner = (cx, cy) => enToLonLat(...enOf(m.containerPointToLatLng([cx, cy])));
      const lls = [corner(0, 0), corner(size.x, 0), corner(0, size.y), corner(size.x, size.y)];
      const xOf = (lon) => (lon + 180) / 360 * k;
      const yOf = (lat) => { const r = lat * Math.PI / 180; return (1 - Math.log(Math.tan(r) + 1 / Math.cos(r)) / Math.PI) / 2 * k; };
      const x0 = Math.max(0, Math.floor(Math.min(...lls.map((p) => xOf(p[0]))))), x1 = Math.min(k - 1, Math.floor(Math.max(...lls.map((p) => xOf(p[0])))));
      const y0 = Math.max(0, Math.floor(Math.min(...lls.map((p) => yOf(p[1]))))), y1 = Math.min(k - 1, Math.floor(Math.max(...lls.map((p) => yOf(p[1])))));
      if ((x1 - x0 + 1) * (y1 - y0 + 1) > 64) return; // zoomed out past the site: not worth a flood of requests
      const toC = (e, n) => { const p = m.latLngToContainerPoint(ll(e, n)); return [p.x, p.y]; };
      for (let y = y0; y <= y1; y++) for (let x = x0; x <= x1; x++) {
        const url = t.url.replace("{z}", z).replace("{x}", x).replace("{y}", y);
        let im = st.webTiles.get(url);
        if (!im) {
          im = new Image(); im.referrerPolicy = "no-referrer"; im.onload = () => this._map && this.draw();
          im.src = url; st.webTiles.set(url, im);
        }
        if (!im.complete || !im.naturalWidth) continue;
        const p = (a, b) => toC(...lonLatToEn(...tileLonLat(z, a, b)));
        const [ax, ay] = p(x, y), [bx, by] = p(x + 1, y), [cx, cy] = p(x, y + 1), W = im.naturalWidth, H = im.naturalHeight;
        ctx.save();
        ctx.setTransform((bx - ax) / W, (by - ay) / W, (cx - ax) / H, (cy - ay) / H, ax, ay);
        ctx.imageSmoothingEnabled = true; ctx.drawImage(im, 0, 0); ctx.restore();
      }
      st.webZoom = z;
    },
  });

  // the ground uncertainty as a heat map: its samples coloured (green 0.1 m .. red 10 m, log) in a
  // small bitmap stretched over the image with bilinear smoothing; the legend in the corner
  const heat = (s) => { // 1-sigma metres -> [r, g, b]
    const t = Math.max(0, Math.min(1, (Math.log10(s) + 1) / 2)); // 0.1 m -> 0, 10 m -> 1
    return t < 0.5 ? [Math.round(510 * t), 200, 60] : [255, Math.round(200 * (2 - 2 * t)), 60];
  };
  function drawHeat(ctx, g, w, h) {
    const cv = document.createElement("canvas"); cv.width = g.nu; cv.height = g.nv;
    const cx = cv.getContext("2d"), id = cx.createImageData(g.nu, g.nv);
    g.sigma_m.forEach((s, k) => {
      const [r, gg, b] = s === null ? [0, 0, 0] : heat(s);
      id.data.set([r, gg, b, s === null ? 0 : 110], 4 * k);
    });
    cx.putImageData(id, 0, 0);
    const [x0, y0] = img.toCanvas(0, 0);
    ctx.save(); ctx.imageSmoothingEnabled = true; ctx.imageSmoothingQuality = "high";
    ctx.drawImage(cv, x0, y0, w * img.s, h * img.s); ctx.restore();
    const L = img.c.width - 190, T = img.c.height - 34; // the legend
    for (let i = 0; i < 150; i++) { const [r, gg, b] = heat(Math.pow(10, -1 + 2 * i / 149)); ctx.fillStyle = `rgb(${r},${gg},${b})`; ctx.fillRect(L + i, T, 1, 10); }
    label(ctx, L, T + 22, "0.1 m", "#fff"); label(ctx, L + 62, T + 22, "1 m", "#fff"); label(ctx, L + 128, T + 22, "10 m", "#fff");
    label(ctx, L, T - 4, "ground 1σ, 1 px detection", "#fff");
  }

  function drawPanel() {
    const S = st.state, s = S.solve, f = (x, n) => (x === null || x === undefined) ? "–" : x.toFixed(n);
    $("title").textContent = `${S.site} · camera ${S.camera.id} · ${S.picks} picks${S.unsaved ? " · unsaved" : ""}`;
    $("undo").disabled = !S.can_undo;
    $("refine").value = S.refine;
    let h;
    if (s.ok) {
      const p = s.position_enu_m, sp = s.sigma_position_enu_m, y = s.yaw_pitch_roll_deg, sy = s.sigma_yaw_pitch_roll_deg;
      h = `<b>pose</b> E ${f(p[0], 3)} ± ${f(sp[0], 3)}, N ${f(p[1], 3)} ± ${f(sp[1], 3)}, U ${f(p[2], 3)} ± ${f(sp[2], 3)} m · ` +
          `yaw ${f(y[0], 3)} ± ${f(sy[0], 3)}°, pitch ${f(y[1], 3)} ± ${f(sy[1], 3)}°, roll ${f(y[2], 3)} ± ${f(sy[2], 3)}° · ` +
          `rms (surveyed) ${f(s.rms_surveyed_px, 3)} px · variance factor ${f(s.variance_factor, 2)} · ` +
          `${s.inliers} inliers, <span class="${s.flagged ? "bad" : ""}">${s.flagged} flagged</span> · solved in ${f(s.time_ms, 1)} ms` +
          (s.warnings ? `<br><span class="bad">${esc(s.warnings)}</span>` : "") +
          `<br><span id="rt" data-rt="${s.rt_cam_enu.join(" ")}">rt_cam_enu ${s.rt_cam_enu.map((x) => x.toFixed(6)).join(" ")}</span>`;
    } else h = `<span class="bad">${esc(s.message)}</span>`;
    $("solve").innerHTML = h;
    const tb = document.querySelector("#landmarks tbody");
    tb.innerHTML = "";
    for (const l of S.landmarks) {
      const tr = document.createElement("tr");
      tr.className = (st.selected === l.id ? "selected " : "") + (l.flagged ? "flagged" : "");
      tr.dataset.id = l.id;
      tr.innerHTML = `<td>${esc(l.id)}</td><td>${esc(l.kind)}</td><td>${f(l.enu_m[0], 2)}, ${f(l.enu_m[1], 2)}</td>` +
        `<td>${l.pick_px ? f(l.pick_px[0], 2) + ", " + f(l.pick_px[1], 2) : ""}</td>` +
        `<td class="res">${l.residual_px ? f(l.residual_norm_px, 3) : ""}</td>` +
        `<td>${l.normalised_residual !== undefined && l.normalised_residual !== null ? f(l.normalised_residual, 2) : ""}</td>` +
        `<td class="flag">${esc(l.flag)}</td>` +
        `<td class="sigma" title="click: this landmark's own sigmas (empty: site.json's)">${f(l.sigma_h_m, 3)}, ${f(l.sigma_v_m, 3)}${l.sigma_stated ? " (own)" : ""}</td>`;
      tr.onclick = () => { st.selected = l.id; render(); };
      tr.querySelector("td.sigma").onclick = (e) => {
        e.stopPropagation();
        const t = window.prompt(`${l.id}: its own 1-sigma horizontal, vertical in metres (empty: the site-wide ones)`,
                                l.sigma_stated ? `${l.sigma_h_m}, ${l.sigma_v_m}` : "");
        if (t === null) return;
        const m = t.trim().match(/^(\d*\.?\d+)\s*[, ]\s*(\d*\.?\d+)$/);
        if (t.trim() && !m) { status("type two numbers: horizontal, vertical sigma in metres", true); return; }
        post("/api/sigma", { landmark: l.id, sigma_h_m: m ? +m[1] : null, sigma_v_m: m ? +m[2] : null });
      };
      tb.appendChild(tr);
    }
  }
  const esc = (t) => String(t).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", "\"": "&quot;" })[c]);

  function render() {
    if (!st.state) return;
    drawImage(); drawMap(); drawPanel();
  }

  // ---- interaction ----
  // A press on a marker (grab answers it) drags the marker: it follows the pointer and is dropped
  // where released (drop); a press elsewhere drags the view; a press without moving is a click.
  function mouse(view, onClick, grab, drop, readout) {
    let down = null;
    const c = view.c;
    const pos = (e) => { // canvas pixels (the canvas may be scaled by CSS until the next resize)
      const r = c.getBoundingClientRect(); return [(e.clientX - r.left) * c.width / r.width, (e.clientY - r.top) * c.height / r.height];
    };
    c.addEventListener("mousedown", (e) => {
      const p = pos(e);
      down = { p, ox: view.ox, oy: view.oy, moved: false, marker: grab(p) };
    });
    c.addEventListener("mousemove", (e) => {
      const p = pos(e);
      readout(...view.toWorld(...p));
      if (!down) return;
      const dx = p[0] - down.p[0], dy = p[1] - down.p[1];
      if (Math.hypot(dx, dy) > 4) down.moved = true;
      if (!down.moved) return;
      if (down.marker && down.marker.fixed) status(`${down.marker.id} is surveyed: it stays where the survey put it (only map picks move)`);
      else if (down.marker) { st.drag = { id: down.marker.id, view: view, at: view.toWorld(...p) }; render(); }
      else { view.ox = down.ox + dx; view.oy = down.oy + dy; render(); }
    });
    c.addEventListener("mouseup", (e) => {
      const w = view.toWorld(...pos(e));
      if (down && !down.moved) onClick(...w);
      else if (down && down.marker && !down.marker.fixed) { st.drag = null; drop(down.marker.id, ...w); }
      down = null;
    });
    c.addEventListener("mouseleave", () => { if (down && down.marker) { st.drag = null; render(); } down = null; });
    c.addEventListener("wheel", (e) => { e.preventDefault(); view.zoom(...pos(e), e.deltaY < 0 ? 1.25 : 0.8); render(); },
                       { passive: false });
  }

  function nearestLandmark(e, n, radiusPx) {
    let best = null, bd = radiusPx;
    const s = mapScale();
    for (const l of st.state.landmarks) {
      const d = Math.hypot(l.enu_m[0] - e, l.enu_m[1] - n) * s;
      if (d < bd) { bd = d; best = l; }
    }
    return best;
  }

  function grabPick(p) { // the pick marker within 8 screen px of canvas point p
    let best = null, bd = 8;
    for (const l of st.state.landmarks) if (l.pick_px) {
      const [x, y] = img.toCanvas(...pxToWorld(l.pick_px[0], l.pick_px[1])), d = Math.hypot(x - p[0], y - p[1]);
      if (d < bd) { bd = d; best = l.id; }
    }
    return best ? { id: best, fixed: false } : null;
  }
  const readoutImage = (X, Y) => { const [u, v] = worldToPx(X, Y); $("readout").textContent = `u ${u.toFixed(2)}, v ${v.toFixed(2)} px`; };
  const readoutMap = (e, n) => {
    const [lon, lat] = enToLonLat(e, n);
    $("readout").textContent = `${lat.toFixed(7)}, ${lon.toFixed(7)} · E ${e.toFixed(2)}, N ${n.toFixed(2)} m`;
  };
  mouse(img, (X, Y) => {
    const [u, v] = worldToPx(X, Y);
    if (st.selected) post("/api/pick", { landmark: st.selected, u, v }).then((ok) => { if (ok) st.selected = null; render(); });
    else if (st.pendingEn) post("/api/landmark", { e: st.pendingEn[0], n: st.pendingEn[1], u, v });
    else { st.pendingPx = [u, v]; status("now click its place on the map"); render(); }
  }, grabPick, (id, X, Y) => { const [u, v] = worldToPx(X, Y); post("/api/pick", { landmark: id, u, v }); }, readoutImage);
  function mapClick(e, n, l) { // a click on the map at ground (e, n), on or near landmark l (may be null)
    if (st.pendingPx) {
      if (l) post("/api/pick", { landmark: l.id, u: st.pendingPx[0], v: st.pendingPx[1] });
      else post("/api/landmark", { e, n, u: st.pendingPx[0], v: st.pendingPx[1] });
    } else if (l) { st.selected = l.id; st.pendingEn = null; status(`${l.id}: now click it in the image`); render(); }
    else { st.selected = null; st.pendingEn = [e, n]; status("new landmark: now click its place in the image"); render(); }
  }

  function step(dir) { // the next / previous landmark without a pick
    const L = st.state.landmarks, k0 = L.findIndex((l) => l.id === st.selected);
    for (let i = 1; i <= L.length; i++) {
      const l = L[((k0 + dir * i) % L.length + L.length) % L.length];
      if (!l.pick_px) { st.selected = l.id; status(`${l.id}: click it in the image`); render(); return; }
    }
  }
  const undo = () => post("/api/undo");
  const save = () => post("/api/save").then((ok) => ok && status("saved: landmarks.geojson and observations"));
  const del = () => { if (st.selected) post("/api/delete", { landmark: st.selected }); };
  $("undo").onclick = undo; $("save").onclick = save; $("delete").onclick = del;
  $("refine").onchange = (e) => post("/api/refine", { refine: e.target.value });
  $("import").onchange = async (e) => {
    const f = e.target.files[0]; if (!f) return;
    if (await post("/api/import", { name: f.name, text: await f.text() })) status(`imported ${f.name}`);
    e.target.value = "";
  };
  $("goto").onsubmit = (e) => { // "lat, lon": moves the selected map pick there, else adds a landmark there
    e.preventDefault();
    const m = $("latlon").value.trim().match(/^(-?\d+(?:\.\d+)?)\s*[,; ]\s*(-?\d+(?:\.\d+)?)$/);
    if (!m) { status("type the point as lat, lon in degrees (WGS84), e.g. 48.1374, 11.5755", true); return; }
    const lat = +m[1], lon = +m[2], sel = st.state.landmarks.find((l) => l.id === st.selected);
    const before = new Set(st.state.landmarks.map((l) => l.id));
    const go = sel && sel.kind === "map-pick" ? post("/api/landmark/move", { landmark: sel.id, lat, lon }) : post("/api/landmark", { lat, lon });
    go.then((ok) => {
      if (!ok) return;
      const l = st.state.landmarks.find((x) => !before.has(x.id)) || sel;
      const [e0, n0] = lonLatToEn(lon, lat);
      lmap.panTo(ll(e0, n0), { animate: false });
      if (l) { st.selected = l.id; status(`${l.id} at ${lat}, ${lon}: now click it in the image`); }
      render();
    });
  };
  $("ground").onchange = (e) => { st.ground = e.target.checked; render(); };
  document.addEventListener("keydown", (e) => {
    const k = e.key;
    if ((e.ctrlKey || e.metaKey) && k === "z") { e.preventDefault(); undo(); }
    else if ((e.ctrlKey || e.metaKey) && k === "s") { e.preventDefault(); save(); }
    else if (e.ctrlKey || e.metaKey || e.altKey) return;
    else if (k === "u") undo();
    else if (k === "s") save();
    else if (k === "Delete" || k === "Backspace") del();
    else if (k === "Escape") { st.selected = null; st.pendingPx = null; st.pendingEn = null; status(""); render(); }
    else if (k === "n") step(1);
    else if (k === "p") step(-1);
    else if (k === "0") { fitImage(); fitMap(); render(); }
    else if (k === "g") { st.ground = !st.ground; $("ground").checked = st.ground; render(); }
  });
  new ResizeObserver(() => { if (size(img.c)) render(); if (lmap) lmap.invalidateSize({ animate: false }); }).observe(document.body);

  // for tests and scripts: where a pixel or a ground point is on the screen (client coordinates)
  window.rsPick = {
    get state() { return st.state; },
    get ready() { return st.ready; },
    toScreen(view, a, b) {
      if (view !== "image") { // the map's container point, as Leaflet places it
        const c = lmap.getContainer(), r = c.getBoundingClientRect(); // unrounded (latLngToContainerPoint rounds)
        const p = lmap.layerPointToContainerPoint(lmap.project(ll(a, b)).subtract(lmap.getPixelOrigin()));
        const k = L.DomUtil.getScale(c); // Leaflet's CSS-pixel scale (a fractional flex width rounds offsetWidth)
        return { x: r.left + (c.clientLeft + p.x) * k.x, y: r.top + (c.clientTop + p.y) * k.y };
      }
      const r = img.c.getBoundingClientRect(), [x, y] = img.toCanvas(...pxToWorld(a, b));
      return { x: r.left + x * r.width / img.c.width, y: r.top + y * r.height / img.c.height };
    },
    toWorld(view, x, y) { // client coordinates -> pixel (u, v) or ground (e, n)
      if (view !== "image") return enOf(lmap.mouseEventToLatLng({ clientX: x, clientY: y })); // as Leaflet reads an event
      const r = img.c.getBoundingClientRect();
      return worldToPx(...img.toWorld((x - r.left) * img.c.width / r.width, (y - r.top) * img.c.height / r.height));
    },
    get orthoLevel() { return st.orthoLevel; },
    get tilesLoaded() { return st.tilesLoaded; },
    get webZoom() { return st.webZoom; },
    zoomMap(e, n, s) { // centre ground point (e, n) at s screen pixels per metre
      lmap.setView(ll(e, n), Math.log2(s / A), { animate: false });
    },
    zoomImage(u, v, s) { // centre pixel (u, v) at s canvas pixels per image pixel
      img.s = s; const [X, Y] = pxToWorld(u, v); img.ox = img.c.width / 2 - s * X; img.oy = img.c.height / 2 - s * Y; render();
    },
  };

  (async function start() {
    size(img.c);
    st.state = await getJSON("/api/state");
    st.map = await getJSON("/api/map");
    const [w, h] = camSize();
    st.image = await rgbCanvas("/api/image.rgb", w, h);
    const kinds = [];
    if (st.map.ortho) kinds.push(`orthophoto (${st.map.ortho.crs}${st.map.ortho.warped ? ", reprojected" : ""}, ` +
                                 `${st.map.ortho.width}x${st.map.ortho.height} cells of ${st.map.ortho.cell_m.toFixed(3)} m)`);
    if (st.map.tiles) kinds.push("web tiles");
    $("mapkind").textContent = kinds.length ? kinds.join(" over ") : "plain map: landmarks and lanes";
    $("attribution").textContent = st.map.tiles ? st.map.tiles.attribution : "";
    createMap();
    fitImage(); fitMap(); onZoom(); render();
    status(st.state.solve.ok ? "solved" : st.state.solve.message);
    st.ready = true;
  })().catch((e) => status(String(e), true));
})();
