// devsim's web page: the plant page (#/), a device page (#/device/NAME) and the running scenario.
// No build step, no library: the server's JSON API and WebSocket (devsim/web/app.py), a canvas chart.
"use strict";

const $ = (sel, root = document) => root.querySelector(sel);
const main = $("#main");
let timers = [];      // the polls of the page shown
let socket = null;    // the WebSocket of the page shown

function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (key === "class") node.className = value;
    else if (key.startsWith("on")) node.addEventListener(key.slice(2), value);
    else if (value !== undefined && value !== null) node.setAttribute(key, value);
  }
  for (const child of children.flat()) {
    if (child !== null && child !== undefined) node.append(child instanceof Node ? child : String(child));
  }
  return node;
}

// A display as the device's front shows it (devsim/observe/monitor_text.py): a 7-segment digit
// and that it blinks, an LCD's lines, a text.
function shownDisplay(value) {
  if (value && typeof value === "object" && !Array.isArray(value)) {
    const char = String(value.char ?? "");
    return (char.trim() ? char : JSON.stringify(char)) + (value.blinking ? " blinking" : "");
  }
  if (Array.isArray(value)) return "[" + value.join(" / ") + "]";
  return value === null || value === undefined ? "–" : String(value);
}

function show(value) {
  if (value === null || value === undefined) return "–";
  if (typeof value === "number") return Number.isInteger(value) ? String(value) : value.toFixed(3);
  if (typeof value === "string") return value;
  return JSON.stringify(value);
}

// -- the API and the token -------------------------------------------------------------------
class Unauthorized extends Error {}

async function api(path, body) {
  const init = body === undefined ? {} : {method: "POST", headers: {"Content-Type": "application/json"},
                                           body: JSON.stringify(body)};
  const response = await fetch(path, init);
  if (response.status === 401) { askToken(); throw new Unauthorized("the token is needed"); }
  const data = await response.json();
  if (!response.ok) throw new Error(data.type ? `${data.type}: ${data.error}` : String(data.error));
  return data;
}

function askToken() {
  const form = $("#login");
  if (!form.hidden) return;
  stop();
  form.hidden = false;
  main.replaceChildren();
  $("#token").focus();
}

async function login(token) {
  const response = await fetch("/api/login", {method: "POST", headers: {"Content-Type": "application/json"},
                                              body: JSON.stringify({token})});
  return response.ok;
}

$("#login").addEventListener("submit", async (event) => {
  event.preventDefault();
  if (await login($("#token").value)) {
    $("#login").hidden = true;
    $("#login-error").textContent = "";
    route();
  } else {
    $("#login-error").textContent = "wrong token";
  }
});

function status(text, bad = false) {
  const node = $("#status");
  node.textContent = text;
  node.className = bad ? "error" : "muted";
}

// -- the chart ------------------------------------------------------------------------------------
// One series against device time, the last WINDOW seconds, motion events as marks.
const WINDOW = 20;
const MIN_SPAN = 2;
const KEEP = 4000;

class Chart {
  constructor(name, unit, clock) {
    this.clock = clock;  // {now}: the device time last heard of, shared by a device's charts
    this.name = name;
    this.unit = unit || "";
    this.points = [];  // [t, value]
    this.marks = [];   // [t, label]
    this.canvas = el("canvas", {class: "chart", "data-series": name, "data-points": "0", "data-marks": "0"});
    this.pending = false;
  }
  add(t, value) {
    this.points.push([t, value]);
    if (this.points.length > KEEP) this.points.splice(0, this.points.length - KEEP);
    this.canvas.dataset.points = String(this.points.length);
    this.canvas.dataset.last = String(value);
    this.draw();
  }
  mark(t, label) {
    this.marks.push([t, label]);
    if (this.marks.length > 200) this.marks.shift();
    this.canvas.dataset.marks = String(this.marks.length);
    this.draw();
  }
  draw() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => { this.pending = false; this.paint(); });
  }
  paint() {
    const canvas = this.canvas;
    const ratio = window.devicePixelRatio || 1;
    const width = canvas.clientWidth, height = canvas.clientHeight;
    if (!width || !height) return;
    canvas.width = width * ratio;
    canvas.height = height * ratio;
    const g = canvas.getContext("2d");
    g.scale(ratio, ratio);
    g.clearRect(0, 0, width, height);
    const end = Math.max(this.clock.now, this.points.length ? this.points[this.points.length - 1][0] : 0);
    // the last WINDOW seconds, or less while there is less to show (at least MIN_SPAN)
    const first = Math.min(this.points.length ? this.points[0][0] : end, ...this.marks.map((m) => m[0]));
    const start = Math.min(end - MIN_SPAN, Math.max(end - WINDOW, first));
    const span = end - start;
    const shown = this.points.filter(([t]) => t >= start);
    if (shown.length) shown.push([end, shown[shown.length - 1][1]]);  // the value holds until now
    let low = Math.min(...shown.map((p) => p[1]), 0), high = Math.max(...shown.map((p) => p[1]), 0);
    if (high - low < 1e-9) { high += 1; low -= 1; }
    const left = 56, right = width - 8, top = 18, bottom = height - 16;
    const x = (t) => left + (t - start) / span * (right - left);
    const y = (v) => bottom - (v - low) / (high - low) * (bottom - top);
    g.font = "11px system-ui, sans-serif";
    g.fillStyle = "#6b7785";
    g.fillText(`${this.name}${this.unit ? " [" + this.unit + "]" : ""}`, left, 12);
    g.fillText(show(high), 2, top + 4);
    g.fillText(show(low), 2, bottom);
    g.fillText(`t = ${end.toFixed(2)} s`, right - 80, 12);
    g.strokeStyle = "#d5dbe1";
    g.beginPath(); g.moveTo(left, y(0)); g.lineTo(right, y(0)); g.stroke();
    for (const [t, label] of this.marks) {
      if (t < start) continue;
      g.strokeStyle = label.includes("end") ? "#1a7f37" : "#9a6700";
      g.beginPath(); g.moveTo(x(t), top); g.lineTo(x(t), bottom); g.stroke();
      g.fillText(label, x(t) + 2, bottom + 12);
    }
    g.strokeStyle = "#0969da";
    g.lineWidth = 1.5;
    g.beginPath();
    shown.forEach(([t, v], i) => (i ? g.lineTo(x(t), y(v)) : g.moveTo(x(t), y(v))));
    g.stroke();
  }
}

// -- the WebSocket ----------------------------------------------------------------------------------
function connect(device, onMessage) {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  const query = device ? `?device=${encodeURIComponent(device)}` : "";
  const ws = new WebSocket(`${scheme}://${location.host}/api/ws${query}`);
  socket = ws;
  ws.onmessage = (event) => onMessage(JSON.parse(event.data));
  ws.onclose = () => {
    if (socket !== ws) return;  // another page took over
    status("the simulator's stream ended: reconnecting", true);
    timers.push(setTimeout(() => { if (socket === ws) connect(device, onMessage); }, 1000));
  };
  ws.onopen = () => status("live");
}

function stop() {
  timers.forEach((t) => { clearInterval(t); clearTimeout(t); });
  timers = [];
  if (socket) { const ws = socket; socket = null; ws.close(); }
}

function every(seconds, fn) {
  fn();
  timers.push(setInterval(fn, seconds * 1000));
}

// -- the plant page ---------------------------------------------------------------------------------
function portRows(ports) {
  return Object.entries(ports).map(([port, p]) => {
    const line = p.line;
    const host = p.connected === true ? `host connected${line && line.host ? " at " + line.host.text : ""}`
      : p.connected === false ? "no host" : "–";
    const mismatch = line && line.mismatch ? el("span", {class: "error"}, " mismatch") : null;
    const faults = line && line.faults.length ? el("span", {class: "error"}, " line faults: " + line.faults.join(", "))
                                              : null;
    return el("tr", {"data-port": port},
      el("td", {}, port), el("td", {class: "mono"}, p.address || "–"),
      el("td", {}, line ? line.device.text : "(not a line)"),
      el("td", {"data-host": port}, host, mismatch, faults));
  });
}

function deviceCard(d) {
  const up = d.ended ? el("span", {class: "badge fault"}, "stopped")
    : d.booting ? el("span", {class: "badge notready"}, "booting") : el("span", {class: "badge ready"}, "up");
  const ready = d.ready === undefined || d.ready === null ? null
    : el("span", {class: `badge ${d.ready ? "ready" : "notready"}`, "data-ready": String(d.ready)},
         d.ready ? "ready" : "not ready");
  const faults = d.faults.length ? el("span", {class: "badge fault"}, "faults: " + d.faults.join(", ")) : null;
  const words = Object.entries(d.state).map(([k, v]) => `${k}=${show(v)}`).join("  ");
  return el("div", {class: "card", "data-device": d.name},
    el("h2", {}, el("a", {href: `#/device/${encodeURIComponent(d.name)}`}, d.name), " ",
       el("span", {class: "muted"}, d.kind), " ", up, " ", ready, " ", faults),
    d.display ? el("div", {}, "display ", el("span", {class: "display"}, d.display)) : null,
    d.message ? el("div", {}, "message ", el("span", {class: "display"}, d.message)) : null,
    el("div", {class: "mono muted"}, words || "(no state yet)"),
    el("h3", {}, "ports"),
    el("table", {}, el("tr", {}, el("th", {}, "port"), el("th", {}, "a host connects to"), el("th", {}, "line"),
                       el("th", {}, "host")), portRows(d.ports)));
}

function scenarioView(s) {
  if (!s) return null;
  const state = s.running ? "running" : s.passed ? "passed" : "failed";
  return el("section", {id: "scenario", "data-state": state},
    el("h2", {}, `scenario ${s.name} `, el("span", {class: s.running ? "muted" : s.passed ? "ok" : "error"}, state)),
    el("div", {}, el("progress", {max: String(s.total || 1), value: String(s.done)}),
       ` step ${s.done} of ${s.total}, ${show(s.now)} of ${show(s.end)} s`),
    s.error ? el("div", {class: "error"}, s.error) : null,
    el("ol", {class: "steps"}, s.steps.map((step) =>
      el("li", {class: step.status, "data-status": step.status},
         `${step.label} — ${step.status}${step.time !== null ? ` at ${show(step.time)} s` : ""}`,
         step.message ? el("div", {class: "muted"}, step.message) : null))));
}

function plantPage() {
  const cards = el("div", {class: "cards", id: "devices"});
  const scenario = el("div");
  main.replaceChildren(scenario, cards);
  every(0.5, async () => {
    try {
      const plant = await api("/api/plant");
      $("#plant-name").textContent = `${plant.name || ""} · ${plant.clock || ""} time`;
      if (!plant.attached) status("waiting for the simulator", true); else status("live");
      cards.replaceChildren(...plant.devices.map(deviceCard));
    } catch (error) { if (!(error instanceof Unauthorized)) status(String(error.message), true); }
  });
  every(0.5, async () => {
    try { scenario.replaceChildren(scenarioView(await api("/api/scenario")) || ""); } catch (error) { /* none */ }
  });
}

// When the simulator stops, the device page waits for the next one at the same address (as
// between the files of `devsim scenario run`) and starts afresh with it.
function reattach(name) {
  stop();
  status("the simulator stopped: waiting for it to start again", true);
  every(1, async () => {
    try {
      const plant = await api("/api/plant");
      if (plant.attached && plant.devices.some((d) => d.name === name && !d.ended)) route();
    } catch (error) { /* not yet */ }
  });
}

// -- the device page -----------------------------------------------------------------------------
const LINE_FAULTS = ["unplug", "hang", "silent", "noise", "baud_mismatch", "corrupt", "drop", "delay"];

async function devicePage(name) {
  let device;
  try { device = await api(`/api/devices/${encodeURIComponent(name)}`); }
  catch (error) { main.replaceChildren(el("p", {class: "error"}, String(error.message))); return; }
  const units = Object.fromEntries(device.points.map((p) => [p.name, p.unit]));
  const clock = {now: device.t || 0};
  const charts = Object.fromEntries(device.charts.map((n) => [n, new Chart(n, units[n], clock)]));
  const faults = new Set(device.faults);
  const values = {};
  const cells = {};
  const dropped = el("span", {class: "muted", id: "dropped"}, "");
  const displays = device.points.filter((p) => /(^|\.)(display|message)$/.test(p.name)).map((p) => p.name);
  const front = el("span", {id: "front"});
  const paintFront = () => front.replaceChildren(...displays.filter((n) => values[n] !== undefined && values[n] !== "")
    .map((n) => el("span", {}, ` ${n} `, el("span", {class: "display"}, shownDisplay(values[n])))));
  $("#plant-name").textContent = name;
  const events = el("ol", {class: "mono", id: "events", reversed: ""});

  // faults, line faults, power cycle
  const faultButtons = el("div", {class: "controls"}, el("strong", {}, "faults"),
    device.info.faults.map((kind) => el("button", {"data-fault": kind, onclick: async (e) => {
      try { await api(`/api/devices/${encodeURIComponent(name)}/fault`, {kind, active: !faults.has(kind)}); }
      catch (error) { e.target.title = error.message; }
    }}, kind)));
  const paintFaults = () => faultButtons.querySelectorAll("button").forEach((b) => {
    b.classList.toggle("on", faults.has(b.dataset.fault));
    b.textContent = `${b.dataset.fault} ${faults.has(b.dataset.fault) ? "on" : "off"}`;
  });
  const lineControls = Object.keys(device.info.ports || {}).map((port) => {
    const kind = el("select", {"data-line-kind": port}, LINE_FAULTS.map((k) => el("option", {value: k}, k)));
    const result = el("span", {class: "muted", "data-line-result": port});
    const send = (active) => async () => {
      try {
        await api(`/api/devices/${encodeURIComponent(name)}/line_fault`, {kind: kind.value, active, port});
        result.textContent = `${kind.value} ${active ? "on" : "off"}`;
        result.className = "muted";
      } catch (error) { result.textContent = error.message; result.className = "error"; }
    };
    return el("div", {class: "controls"}, el("strong", {}, `line ${port}`), kind,
              el("button", {onclick: send(true), "data-line-on": port}, "start"),
              el("button", {onclick: send(false), "data-line-off": port}, "end"), result);
  });
  const cycle = el("button", {id: "power-cycle", onclick: async () => {
    try { await api(`/api/devices/${encodeURIComponent(name)}/power_cycle`, {}); status("power cycled"); }
    catch (error) { status(error.message, true); }
  }}, "power cycle");

  // the points
  const filter = el("input", {placeholder: "filter names", id: "filter", oninput: () => {
    const text = filter.value.toLowerCase();
    for (const row of table.querySelectorAll("tr[data-point]")) row.hidden = !row.dataset.point.toLowerCase().includes(text);
  }});
  const table = el("table", {id: "points"}, el("tr", {}, el("th", {}, "name"), el("th", {}, "value"),
    el("th", {}, "unit"), el("th", {}, "set"), el("th", {}, "")));
  for (const p of device.points) {
    const value = el("td", {class: "value"}, p.access.includes("r") ? "–" : "(set only)");
    cells[p.name] = value;
    let setter = el("td", {});
    const message = el("td", {class: "error"});
    if (p.access.includes("w")) {
      const input = el("input", {class: "set", "data-set": p.name, "aria-label": `set ${p.name}`});
      const set = async () => {
        try {
          await api(`/api/devices/${encodeURIComponent(name)}/set`, {name: p.name, value: input.value});
          message.textContent = ""; message.className = "ok"; message.textContent = "set";
        } catch (error) { message.className = "error"; message.textContent = error.message; }
      };
      input.addEventListener("keydown", (e) => { if (e.key === "Enter") set(); });
      setter = el("td", {}, input, el("button", {onclick: set, "data-set-button": p.name}, "set"));
    }
    table.append(el("tr", {"data-point": p.name, title: `${p.doc} (${p.section})`},
                       el("td", {class: "mono"}, p.name), value, el("td", {}, p.unit || ""), setter, message));
  }

  // the traffic
  let paused = false;
  const pause = el("button", {id: "pause", onclick: () => {
    paused = !paused;
    pause.textContent = paused ? "resume" : "pause";
  }}, "pause");
  const traffic = Object.keys(device.info.ports || {}).map((port) => {
    const body = el("tbody", {"data-traffic": port});
    every(0.5, async () => {
      if (paused) return;
      try {
        const telegrams = await api(`/api/devices/${encodeURIComponent(name)}/telegrams?port=${encodeURIComponent(port)}&count=50`);
        body.replaceChildren(...telegrams.slice().reverse().map((t) => el("tr", {},
          el("td", {}, t.t.toFixed(3)), el("td", {class: `dir-${t.dir}`}, t.dir), el("td", {}, t.text),
          el("td", {}, (t.decoded || []).map((d) => typeof d === "object"
            ? Object.entries(d).map(([k, v]) => `${k}=${show(v)}`).join(" ") : show(d)).join("; ")))));
      } catch (error) { body.replaceChildren(el("tr", {}, el("td", {class: "muted"}, error.message))); }
    });
    return el("div", {}, el("h3", {}, `port ${port}`), el("div", {class: "traffic"}, el("table", {}, body)));
  });

  main.replaceChildren(
    el("section", {}, el("h2", {}, `${name} `, el("span", {class: "muted"}, device.info.kind), " ",
                         el("a", {href: "#/"}, "plant")),
       el("div", {class: "controls"}, cycle, front, dropped), faultButtons, lineControls),
    el("section", {}, el("h2", {}, "axes"), el("div", {class: "charts"}, Object.values(charts).map((c) => c.canvas))),
    el("section", {}, el("h2", {}, "points ", filter), el("div", {class: "points"}, table)),
    el("section", {}, el("h2", {}, "traffic, newest first ", pause), traffic),
    el("section", {}, el("h2", {}, "events, newest first"), events));

  const mark = (item) => {
    if (item.type === "ended") { reattach(name); return; }
    const text = item.name || item.code || item.text || "";
    const label = item.type === "event" ? text : `${item.type} ${text}`;
    events.prepend(el("li", {}, `${show(item.t)} ${label}${item.type === "fault" ? (item.active ? " on" : " off") : ""}`));
    while (events.childElementCount > 200) events.lastChild.remove();
    if (item.type === "event" && /move|motion|stop|hom/i.test(text)) Object.values(charts).forEach((c) => c.mark(item.t, text));
    if (item.type === "fault") { (item.active ? faults.add(item.name) : faults.delete(item.name)); paintFaults(); }
  };
  const change = (item) => {
    values[item.name] = item.value;
    if (cells[item.name]) cells[item.name].textContent = show(item.value);
    if (displays.includes(item.name)) paintFront();
  };
  paintFaults();
  connect(name, (message) => {
    if (message.snapshot) {
      const snap = message.snapshot[name];
      Object.entries(snap.values).forEach(([k, v]) => change({name: k, value: v}));
      faults.clear(); snap.faults.forEach((f) => faults.add(f)); paintFaults();
      events.replaceChildren();
      snap.events.forEach(mark);
      return;
    }
    const times = [...message.values, ...message.points, ...message.events].map((i) => i.t).filter(Number.isFinite);
    if (times.length) clock.now = Math.max(clock.now, ...times);
    message.values.forEach(change);
    message.points.forEach((p) => charts[p.name] && charts[p.name].add(p.t, p.value));
    message.events.forEach(mark);
    Object.values(charts).forEach((c) => c.draw());
    dropped.textContent = message.dropped ? `chart points dropped: ${message.dropped}` : "";
  });
}

// -- routes -----------------------------------------------------------------------------------------
async function route() {
  stop();
  const hash = location.hash;
  const token = /token=([^&]+)/.exec(hash);
  if (token) {
    history.replaceState(null, "", location.pathname + "#/");
    await login(decodeURIComponent(token[1]));
  }
  const match = /^#\/device\/(.+)$/.exec(location.hash);
  if (match) devicePage(decodeURIComponent(match[1])); else plantPage();
}

window.addEventListener("hashchange", route);
route();
