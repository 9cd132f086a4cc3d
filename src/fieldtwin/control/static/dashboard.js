// The fieldtwin dashboard (docs/dashboard.md): a client of the control API, nothing more.
// It polls GET /dashboard/state, draws the fronts, sends every command to the API's own
// resources, and listens to GET /events for the traffic.  Every buffer is a bounded ring.

const BODY = document.body;
const PARAMS = new URLSearchParams(location.search);
// a token comes in the first page's URL only (the plant keeps it in an HttpOnly cookie):
// it is taken out of the address bar and history at once, and used from memory
const TOKEN = PARAMS.get("token") || "";
if (PARAMS.has("token")) {
  const clean = new URL(location.href);
  clean.searchParams.delete("token");
  history.replaceState(null, "", clean);
}
const RATE = Math.max(1, Math.min(20, Number(PARAMS.get("rate") || BODY.dataset.rate) || 5));
const TREND_POINTS = 3000; // points kept per series (a ring)
const TRAFFIC_KEPT = 1000; // events kept for the traffic view (a ring)
const TRAFFIC_SHOWN = 200; // rows drawn
const LED_COLOURS = { OK: "green", ERR: "red", F: "red", Pwr: "green", Run: "green", Prm: "green", Wdg: "red" };

const stats = { updates: 0, events: 0, errors: 0, lastError: "", state: null, rate: RATE };
window.__fieldtwin = stats;

// --- the API -------------------------------------------------------------------------

async function api(method, path, body) {
  // every request that changes the plant carries a JSON body ({} when the route takes
  // none): the plant refuses one without (415), as an HTML form would send it
  const headers = { "content-type": "application/json" };
  if (TOKEN) headers.authorization = `Bearer ${TOKEN}`;
  const changes = method !== "GET" && method !== "HEAD";
  const answer = await fetch(path, {
    method, headers, credentials: "same-origin",
    body: changes ? JSON.stringify(body === undefined ? {} : body) : undefined,
  });
  let data = null;
  try { data = await answer.json(); } catch (_) { data = null; }
  if (!answer.ok) {
    const text = data && data.error ? data.error : `${answer.status} ${answer.statusText}`;
    throw new Error(text);
  }
  return data;
}

const errorBox = document.getElementById("error");
function showError(text, where) {
  stats.errors += 1;
  stats.lastError = text;
  errorBox.textContent = text;
  errorBox.hidden = false;
  if (where) { where.textContent = text; where.className = "msg bad"; }
}
function showOk(text, where) {
  errorBox.hidden = true;
  if (where) { where.textContent = text; where.className = "msg ok"; }
}
// A TES's power cycle: at once, or an outage of some simulated seconds (POST .../power-cycle
// {"seconds": S}, 0..3600); during it the TES does not answer and its LEDs are off.
function powerCycleControls(base, msg) {
  const seconds = el("input", { class: "args outage", type: "number", min: "0", max: "3600", step: "any", size: "5", placeholder: "off s", title: "simulated seconds off (empty: off and on at once)" });
  const button = el("button", { type: "button", class: "power-cycle" }, "power cycle");
  button.addEventListener("click", () => {
    const s = seconds.value.trim() === "" ? 0 : Number(seconds.value);
    if (!(s >= 0 && s <= 3600)) { showError(`power cycle: ${seconds.value} not allowed (0 to 3600 simulated seconds)`, msg); return; }
    command("POST", `${base}/power-cycle`, s ? { seconds: s } : undefined, msg, s ? `power off for ${s} s` : "power cycled");
  });
  return [button, seconds];
}

async function command(method, path, body, where, okText) {
  try {
    const data = await api(method, path, body);
    showOk(okText || "ok", where);
    return data;
  } catch (exc) {
    showError(`${method} ${path}: ${exc.message}`, where);
    return null;
  }
}

// --- small helpers ---------------------------------------------------------------------

function esc(text) {
  return String(text ?? "").replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" })[c]);
}
function el(tag, attrs, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs || {})) {
    if (key === "class") node.className = value;
    else if (key.startsWith("on")) node.addEventListener(key.slice(2), value);
    else node.setAttribute(key, value);
  }
  for (const child of children) node.append(child);
  return node;
}
function led(name, state) {
  const colour = LED_COLOURS[name] || "amber";
  return `<span class="ledbox"><span class="led ${colour} led-${esc(state)}" data-led="${esc(name)}" title="${esc(name)} ${esc(state)}"></span>${esc(name)}</span>`;
}
function bitRow(label, value, count, what) {
  if (value === null || value === undefined) return "";
  let cells = "";
  for (let i = count - 1; i >= 0; i -= 1) {
    const on = (value >> i) & 1;
    cells += `<span class="bit ${on ? "on" : ""}" data-${what}="${i.toString(16).toUpperCase()}" title="${label},${i.toString(16).toUpperCase()} = ${on}">${i.toString(16).toUpperCase()}</span>`;
  }
  return `<div class="bits"><span class="lbl">${label}</span>${cells}</div>`;
}
function signed(v) { return v === null || v === undefined ? "-" : v & 0x8000 ? v - 0x10000 : v; }
function parseNumber(text) {
  const t = String(text).trim();
  const h = /^H'([0-9A-Fa-f]+)'$/.exec(t);
  if (h) return parseInt(h[1], 16);
  if (/^0x[0-9a-f]+$/i.test(t)) return parseInt(t, 16);
  if (/^-?\d+$/.test(t)) return parseInt(t, 10);
  return NaN;
}
function parseParams(text) {
  // "offset=5 amplitude=4 period_s=60" -> { offset: 5, amplitude: 4, period_s: 60 }
  const out = {};
  for (const part of String(text).trim().split(/[\s,]+/).filter(Boolean)) {
    const [key, value] = part.split("=");
    if (!key || value === undefined || value === "") throw new Error(`${part}: write name=value`);
    const number = Number(value);
    out[key] = value === "true" ? true : value === "false" ? false : Number.isFinite(number) ? number : value;
  }
  return out;
}

// --- the fronts ------------------------------------------------------------------------

const panels = new Map(); // id -> { root, display, html }
const refits = new Map(); // "kind:id:input" -> fits a slider to the input's range now
const lastSerial = new Map(); // "slot channel dir" -> last text block seen

function analogOutputsHtml(outputs) { // the outputs in the device's units, the word beside (bits: the O row)
  const shown = (outputs || []).filter((o) => typeof o.value !== "boolean");
  if (!shown.length) return "";
  return `<table class="meas"><tr><th>output</th><th>value</th><th>word</th></tr>` +
    shown.map((o) => `<tr><td>${esc(o.name)}</td><td data-aout="${esc(o.name)}">${Number(o.value).toFixed(3)} ${esc(o.unit)}</td><td>${o.raw === null ? "-" : "H'" + o.raw.toString(16).toUpperCase().padStart(4, "0") + "'"}</td></tr>`).join("") + "</table>";
}
function faultNote(d) { // the faults in force, whoever set them (the page, the API, the console)
  const active = d.active_faults || [];
  return active.length ? `<div class="alarm" data-f="faults">fault: ${esc(active.join(", "))}</div>` : "";
}
let pollsStarted = 0; // state requests sent so far
let drawingPoll = 0; // the request whose answer is being drawn
function syncFaults(panel, dev) { // each fault button shows whether its fault is in force now
  for (const fault of dev.faults || []) {
    const button = panel.root.querySelector(`button.fault[data-fault="${CSS.escape(fault.name)}"]`);
    // an answer to a request sent before the button's own command is older than it
    if (!button || Number(button.dataset.sentBefore || 0) >= drawingPoll) continue;
    button.classList.toggle("active", Boolean(fault.active));
  }
}

function moduleHtml(m) {
  if (!m.present) return removedModuleHtml(m);
  const head = `<div class="head"><b>slot ${esc(m.address)}</b> <span class="kind">${esc(m.kind)}</span>
    <span class="state" data-f="state">${esc(m.present ? m.state : "removed")}${m.mode ? " · " + esc(m.mode) : ""}</span></div>` + faultNote(m);
  const leds = `<div class="leds">${m.leds.map(([n, s]) => led(n, s)).join("")}
    <span class="is">I,S <b data-f="is">${m.is}</b></span></div>`;
  const bits = bitRow(`I${m.address}`, m.i_bits, m.points, "i") + bitRow(`O${m.address}`, m.o_bits, m.points, "o");
  let words = "";
  if (!m.kind.startsWith("TSX DET") && !m.kind.startsWith("TSX DST")) {
    words = `<table class="words"><tr><th>IW</th><th>hex</th><th>dec</th><th>OW</th><th>hex</th></tr>`;
    for (let i = 0; i < 8; i += 1) {
      const iw = m.iw[i], ow = m.ow[i];
      words += `<tr><td>${esc(iw.name)}</td><td data-w="${esc(iw.name)}">${esc(iw.hex)}</td><td>${signed(iw.value)}</td>
        <td>${esc(ow.name)}</td><td data-w="${esc(ow.name)}">${esc(ow.hex)}</td></tr>`;
    }
    words += "</table>";
  }
  return head + leds + bits + words + analogOutputsHtml(m.outputs) + decodedHtml(m);
}

function decodedHtml(m) {
  const d = m.decoded || {};
  if (m.kind.startsWith("TSX AEM")) {
    let rows = "";
    for (const ch of d.channels || []) {
      rows += `<tr><td>${ch.channel}</td><td class="meas" data-meas="${ch.channel}">${ch.value ?? "-"}</td><td>${esc(ch.text)}</td></tr>`;
    }
    return `<div class="decoded"><div class="muted">${esc(d.configuration)} · ${esc(d.sampling)}</div>
      <table class="meas"><tr><th>ch</th><th>measurement</th><th>range, scaling, thresholds</th></tr>${rows}</table></div>`;
  }
  if (m.kind.startsWith("TSX DEM")) {
    const msgs = (d.messages || []).map((x) => `<tr><td>${esc(x.stamp)}</td><td>${esc(x.what)}${x.h ? " (H)" : ""}</td></tr>`).join("");
    return `<div class="decoded"><div>module time <b data-f="time">${esc(d.time)}</b></div>
      <div>stack <b data-f="stack">${d.fill}/${d.size}</b> ${d.overflow ? `<span class="alarm">overflow, ${d.lost} lost</span>` : "no overflow"}
      · logging ${esc(d.logging)} · sync fault ${esc(d.sync_fault)}</div>
      <table class="msgs"><tr><th>time stamp</th><th>message</th></tr>${msgs || '<tr><td colspan="2" class="muted">no message stacked</td></tr>'}</table></div>`;
  }
  if (m.kind.startsWith("TSX SCM")) {
    const rows = (d.channels || []).map((c) => {
      const rx = lastSerial.get(`${m.address} ${c.channel} in`) || "";
      const tx = lastSerial.get(`${m.address} ${c.channel} out`) || "";
      return `<tr><td>${c.channel}</td><td>${esc(c.text)}</td></tr>
        <tr><td></td><td>received <code data-rx="${c.channel}">${esc(rx)}</code> · sent <code data-tx="${c.channel}">${esc(tx)}</code></td></tr>`;
    }).join("");
    return `<div class="decoded"><div>${esc(d.activity)}</div><table class="msgs">${rows}</table></div>`;
  }
  return frontHtml(m.panel); // a kind without a layout of its own: its typed front, as it is
}

function frontHtml(p) {
  // any device's typed front panel (Device.panel()): bit rows, words, readings with unit and
  // flags, frozen values, fields, log; the LEDs are drawn with the head
  if (!p) return "";
  const value = (r) => r.value === null || r.value === undefined ? "-"
    : typeof r.value === "number" && !Number.isInteger(r.value) ? r.value.toFixed(3) : String(r.value);
  const readings = (title, list, what) => list.length ? `<table class="meas"><tr><th>${title}</th><th>value</th><th>flags</th><th></th></tr>` +
    list.map((r) => `<tr><td>${esc(r.name)}</td><td data-${what}="${esc(r.name)}">${esc(value(r))} ${esc(r.unit)}</td>
      <td class="${r.flags.length ? "alarm" : ""}" data-flags="${esc(r.name)}">${esc(r.flags.join(", "))}</td><td>${esc(r.text)}</td></tr>`).join("") + "</table>" : "";
  const rows = p.bits.map((r) => `<div class="bits" data-row="${esc(r.name)}"><span class="lbl">${esc(r.name)}</span>` +
    r.bits.map((on, i) => [on, i]).reverse().map(([on, i]) => `<span class="bit ${on ? "on" : ""}" title="${esc(r.name)} ${i} = ${on ? 1 : 0}">${i}</span>`).join("") + "</div>").join("");
  const words = p.words.length ? `<table class="words"><tr><th>word</th><th>hex</th><th>dec</th></tr>` +
    p.words.map((w) => `<tr><td>${esc(w.name)}</td><td data-word="${esc(w.name)}">${w.value === null ? "-" : "H'" + (w.value & 0xffff).toString(16).toUpperCase().padStart(4, "0") + "'"}</td><td>${w.value ?? "-"}</td></tr>`).join("") + "</table>" : "";
  const fields = Object.entries(p.fields || {});
  const facts = fields.length ? `<div class="muted front-fields">${fields.map(([k, v]) => `${esc(k)} <b data-field="${esc(k)}">${esc(String(v))}</b>`).join(" · ")}</div>` : "";
  const log = p.log.length ? `<table class="msgs"><tr><th>time stamp</th><th>logged</th></tr>` +
    p.log.slice(0, 8).map((x) => `<tr><td>${esc(x.stamp)}</td><td>${esc(x.what)}</td></tr>`).join("") + "</table>" : "";
  return `<div class="decoded front">${facts}${rows}${words}${readings("reading", p.readings, "reading")}${readings("frozen", p.frozen, "frozen")}${log}</div>`;
}

function deviceHtml(d) { // a device outside the rack of a family without a layout of its own
  const head = `<div class="head"><b>${esc(d.label)}</b> <span class="kind">${esc(d.kind)}</span>
    <span class="state" data-f="state">${esc(d.state)} ${esc(d.status)}</span></div>
    <div class="muted">${esc(d.where)}</div>`;
  const leds = `<div class="leds">${d.leds.map(([n, s]) => led(n, s)).join("")}</div>`;
  return head + faultNote(d) + leds + frontHtml(d.panel) + analogOutputsHtml(d.analog_outputs);
}

function tesHtml(t) {
  const head = `<div class="head"><b>TES ${t.slave}</b> <span class="kind">${esc(t.kind)}</span>
    <span class="state" data-f="state">${esc(t.state)} ${esc(t.status)}</span></div>
    <div class="muted">${esc(t.endpoint)}</div>`;
  const leds = `<div class="leds">${t.leds.map(([n, s]) => led(n, s)).join("")}</div>`;
  const pack = (list) => list.reduce((acc, on, i) => acc | ((on ? 1 : 0) << i), 0) >>> 0;
  let io = "";
  if (t.inputs.length) io += bitRow("in", pack(t.inputs), t.inputs.length, "in");
  if (t.outputs.length) io += bitRow("out", pack(t.outputs), t.outputs.length, "out");
  let analog = "";
  if (t.analog.length) {
    analog = `<table class="meas"><tr><th>input</th><th>${esc(t.analog[0].unit)}</th><th>points</th></tr>` +
      t.analog.map((a) => `<tr><td>${a.input}</td><td data-volts="${a.input}">${a.level.toFixed(3)}</td><td data-points="${a.input}">${a.points}</td></tr>`).join("") + "</table>";
  }
  let counters = "";
  if (t.counters.length) {
    counters = `<details class="counters"><summary>counters</summary><table class="meas"><tr><th>input</th><th>rises</th><th>falls</th></tr>` +
      t.counters.map((c) => `<tr><td>${c.input}</td><td>${c.rise}</td><td>${c.fall}</td></tr>`).join("") + "</table></details>";
  }
  const aout = analogOutputsHtml(t.analog_outputs);
  const wd = t.watchdog ? `<div>watchdog <b>${t.watchdog.seconds} s</b>${t.watchdog.word ? "" : " (off)"} · Wdg ${esc(t.watchdog.led)}</div>` : "";
  return head + faultNote(t) + leds + io + analog + aout + wd + lastRequestHtml(t) + counters;
}

function controlsFor(kind, dev, ident) {
  // built once per device: inputs, signal presets, faults, and the device's own actions
  const box = el("details", { class: "ctl" }, el("summary", {}, "controls"));
  const msg = el("span", { class: "msg" });
  const base = `/devices/${encodeURIComponent(ident)}`;
  const inputs = kind === "tes" ? dev.analog.map((a) => a.input).concat(dev.inputs.map((_, i) => String(i)))
    : kind === "module" ? dev.inputs : dev.input_names || [];
  const analog = (name) => kind === "tes" ? name.startsWith("a")
    : dev.kind.startsWith("TSX AEM") || /^analog/.test((dev.input_kinds || {})[name] || "");
  const discrete = (name) => !analog(name) && !dev.kind.startsWith("TSX SCM");
  for (const name of inputs) {
    const row = el("div", { class: "input-row", "data-input": name }, el("span", { class: "lbl" }, `in ${name}`));
    if (discrete(name)) {
      row.append(el("button", { type: "button", class: "toggle", onclick: () => toggle(kind, ident, name, msg) }, "toggle"));
    } else {
      const field = el("input", { class: "value", size: "7", placeholder: analog(name) ? (kind === "tes" ? "5.0" : "12mA") : "CTS=1" });
      row.append(field, el("button", { type: "button", class: "set", onclick: () => setInput(base, name, field.value, msg) }, "set"));
      if (analog(name)) {
        const slider = el("input", { type: "range", class: "slider", step: "0.1" });
        const unitLabel = el("span", { class: "unit" });
        const fit = (d) => { // the channel's range as configured now (an AEM's changes at its configuration)
          const unit = kind === "tes" ? "V" : aemUnit(d, name);
          const [lo, hi] = unit === "mA" ? [0, 20] : kind === "tes" ? [0, 10] : [-10, 10];
          if (slider.dataset.unit !== unit) {
            slider.dataset.unit = unit;
            slider.min = lo; slider.max = hi; slider.value = lo;
            unitLabel.textContent = unit;
            field.placeholder = kind === "tes" ? "5.0" : unit === "mA" ? "12mA" : "2.5V";
          }
        };
        fit(dev);
        refits.set(`${kind}:${ident}:${name}`, fit);
        slider.addEventListener("change", () => {
          const text = kind === "tes" ? slider.value : `${slider.value}${slider.dataset.unit}`;
          field.value = text;
          setInput(base, name, text, msg);
        });
        row.append(slider, unitLabel);
      }
    }
    if (!dev.kind.startsWith("TSX SCM")) {
      const preset = el("select", { class: "preset" });
      const presets = analog(name) ? ANALOG_PRESETS : DISCRETE_PRESETS;
      for (const key of Object.keys(presets)) preset.append(el("option", { value: key }, key));
      const args = el("input", { class: "args", size: "22", value: presets[preset.value] });
      preset.addEventListener("change", () => { args.value = presets[preset.value]; });
      row.append(preset, args, el("button", { type: "button", class: "drive", onclick: () => drive(base, name, preset.value, args.value, analog(name), msg) }, "drive"));
    }
    box.append(row);
  }
  const faults = el("div", { class: "faults" }, el("span", { class: "lbl" }, "faults"));
  for (const fault of dev.faults) { // the faults that apply to this device, as its face lists them
    const params = el("input", { class: "args", size: "8", placeholder: fault.hint || "" });
    const needs = (fault.takes || []).length > 0;
    const button = el("button", { type: "button", class: fault.active ? "fault active" : "fault", "data-fault": fault.name, title: fault.description }, fault.name);
    button.addEventListener("click", async () => {
      const active = !button.classList.contains("active");
      let body;
      try { body = { active, params: needs && active ? numbers(parseParams(params.value)) : {} }; } catch (exc) { showError(`${fault.name}: ${exc.message}`, msg); return; }
      const done = await command("PUT", `${base}/faults/${encodeURIComponent(fault.name)}`, body, msg, `${fault.name} ${active ? "set" : "cleared"}`);
      if (done) { button.classList.toggle("active", active); button.dataset.sentBefore = String(pollsStarted); }
    });
    faults.append(button);
    if (needs) faults.append(params);
  }
  box.append(faults);
  const actions = el("div", { class: "actions" });
  if (kind === "tes") {
    actions.append(...powerCycleControls(base, msg));
  } else {
    actions.append(
      el("button", { type: "button", class: "remove", onclick: () => command("POST", "/plc/remove", { module: dev.address }, msg, "removed") }, "remove module"),
      el("button", { type: "button", class: "insert", onclick: () => command("POST", "/plc/insert", { module: dev.address }, msg, "inserted") }, "insert module"),
    );
  }
  box.append(writeObjectRow(kind, dev, base, msg), actions, msg);
  return box;
}

const ANALOG_PRESETS = {
  constant: "value=5",
  ramp: "start=0 end=10 t0_s=0 duration_s=60",
  sine: "offset=5 amplitude=4 period_s=30",
  "pulse train": "low=0 high=10 period_s=10 duty=0.5",
};
const DISCRETE_PRESETS = {
  constant: "value=true",
  "pulse train": "period_s=2 duty=0.5",
};
function numbers(params) {
  for (const [key, value] of Object.entries(params)) {
    if (typeof value !== "number") throw new Error(`${key}=${value}: a number`);
  }
  return params;
}
function aemUnit(dev, name) {
  const channel = (dev.decoded.channels || [])[Number(name)];
  return channel && /mA/.test(channel.text) ? "mA" : "V";
}
async function setInput(base, name, text, msg) {
  const value = String(text).trim();
  if (!value) { showError(`input ${name}: type a value`, msg); return; }
  const number = Number(value);
  const body = { value: value !== "" && Number.isFinite(number) ? number : value };
  await command("PUT", `${base}/inputs/${encodeURIComponent(name)}`, body, msg, `input ${name} = ${value}`);
}
async function toggle(kind, ident, name, msg) {
  const state = stats.state;
  let now = false;
  if (kind === "tes") {
    const t = state.tes.find((x) => x.id === ident);
    now = Boolean(t && t.inputs[Number(name)]);
  } else {
    const m = state.modules.find((x) => x.id === ident);
    if (m && m.i_bits !== null) now = Boolean((m.i_bits >> parseInt(name, 16)) & 1);
    if (m && m.kind.startsWith("TSX DEM")) now = Boolean((parseInt((m.details.inputs || "H'0'").slice(2), 16) >> Number(name)) & 1);
  }
  await command("PUT", `/devices/${encodeURIComponent(ident)}/inputs/${encodeURIComponent(name)}`, { value: !now }, msg, `input ${name} -> ${!now ? 1 : 0}`);
}
async function drive(base, name, preset, text, analog, msg) {
  let params;
  try { params = parseParams(text); } catch (exc) { showError(`input ${name}: ${exc.message}`, msg); return; }
  let signal;
  if (preset === "constant") signal = { kind: "constant", ...params };
  else if (preset === "pulse train") signal = { kind: analog ? "square" : "pulse", ...params };
  else signal = { kind: preset, ...params };
  await command("PUT", `${base}/inputs/${encodeURIComponent(name)}`, { signal }, msg, `input ${name}: ${preset}`);
}

function ensurePanel(container, kind, dev) {
  let panel = panels.get(`${kind}:${dev.id}`);
  if (!panel) {
    const display = el("div", { class: "display" });
    const root = el("article", { class: `panel ${kind}`, id: `${kind === "module" ? "mod" : kind}-${dev.id}` }, display);
    root.append(controlsFor(kind, dev, dev.id));
    container.append(root);
    panel = { root, display, html: "" };
    panels.set(`${kind}:${dev.id}`, panel);
  }
  return panel;
}

function draw(state) {
  stats.state = state;
  document.getElementById("title").textContent = state.title;
  const clock = state.clock;
  document.getElementById("clock").textContent = `t = ${clock.t_s.toFixed(1)} s${clock.paused ? " (paused)" : ""}`;
  document.getElementById("speed").textContent = `speed ${clock.speed === "max" ? "max" : "x" + clock.speed}`;
  if (!stats.updates) document.getElementById("speed-value").value = String(clock.speed); // the plant's, at first
  if (state.plc) {
    document.getElementById("plc-model").textContent = state.plc.model;
    const mode = document.getElementById("plc-mode");
    mode.textContent = state.plc.fault ? `${state.plc.mode}: ${state.plc.fault}` : state.plc.mode;
    mode.title = state.plc.fault || "";
    mode.classList.toggle("stop", !state.plc.running);
    document.getElementById("plc-scan").textContent = `master task ${state.plc.scan_ms} ms`;
  }
  const modules = document.getElementById("modules");
  for (const m of state.modules) {
    const panel = ensurePanel(modules, "module", m);
    const html = moduleHtml(m);
    if (html !== panel.html) { panel.display.innerHTML = html; panel.html = html; }
    syncFaults(panel, m);
    for (const name of m.inputs) refits.get(`module:${m.id}:${name}`)?.(m);
  }
  const tesList = document.getElementById("tes-list");
  for (const t of state.tes) {
    const panel = ensurePanel(tesList, "tes", t);
    const html = tesHtml(t);
    if (html !== panel.html) { panel.display.innerHTML = html; panel.html = html; }
    syncFaults(panel, t);
  }
  for (const family of state.families || []) { // a family of devices with no layout of its own
    if (family.key === "tes") continue;
    let list = document.getElementById(`family-${family.key}`);
    if (!list) {
      list = el("div", { class: "grid", id: `family-${family.key}` });
      document.getElementById("tes").after(el("section", {}, el("h2", {}, family.title), list));
    }
    for (const d of state[family.key] || []) {
      const panel = ensurePanel(list, family.key, d);
      const html = deviceHtml(d);
      if (html !== panel.html) { panel.display.innerHTML = html; panel.html = html; }
      syncFaults(panel, d);
    }
  }
  drawTags(state);
  trends.sample(state);
}

// --- the poll loop -------------------------------------------------------------------------

const link = document.getElementById("link");
const MAX_IN_FLIGHT = 2; // a slow answer does not halve the rate; a third waits its turn
let inFlight = 0;
let drawnAt = -1; // t_us of the newest state drawn: an older answer is not drawn over it
async function poll() {
  if (inFlight >= MAX_IN_FLIGHT) return;
  inFlight += 1;
  const seq = ++pollsStarted;
  try {
    const state = await api("GET", "/dashboard/state");
    if (state.clock.t_us >= drawnAt) {
      drawnAt = state.clock.t_us;
      drawingPoll = seq;
      draw(state);
      stats.updates += 1;
    }
    link.textContent = `${RATE}/s`;
    link.className = "muted";
    plantAnswers();
  } catch (exc) {
    link.textContent = `no answer: ${exc.message}`;
    link.className = "alarm";
    plantSilent(exc);
  } finally {
    inFlight -= 1;
  }
}
function startPolling() {
  poll();
  setInterval(poll, 1000 / RATE);
}

// --- the clock and the PLC ---------------------------------------------------------------------

function wireHeader() {
  const get = (id) => document.getElementById(id);
  get("pause").addEventListener("click", () => command("POST", "/clock/pause", undefined, null, "paused"));
  get("resume").addEventListener("click", () => command("POST", "/clock/resume", undefined, null, "resumed"));
  get("step").addEventListener("click", () => {
    const ms = Number(get("step-ms").value);
    if (!Number.isFinite(ms) || get("step-ms").value.trim() === "") { showError(`step: ${get("step-ms").value} is not a number of ms`); return; }
    command("POST", "/clock/step", { ms }, null, "stepped");
  });
  get("set-speed").addEventListener("click", () => {
    const text = get("speed-value").value.trim();
    const speed = text === "max" ? "max" : Number(text);
    if (speed !== "max" && (!Number.isFinite(speed) || text === "")) { showError(`speed: ${text} is not a number or max`); return; }
    command("PUT", "/clock/speed", { speed }, null, "speed set");
  });
  get("power-break").addEventListener("click", () => {
    const seconds = Number(get("break-s").value);
    if (!Number.isFinite(seconds) || get("break-s").value.trim() === "") { showError(`power break: ${get("break-s").value} is not seconds`); return; }
    command("POST", "/plc/power-break", { seconds }, null, "power back");
  });
}

// --- the Text Block panel -----------------------------------------------------------------------

function wireTextBlock() {
  const form = document.getElementById("txt-form");
  const out = document.getElementById("txt-result");
  const show = (field, value) => { out.querySelector(`[data-f="${field}"]`).textContent = value; };
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const f = form.elements;
    const body = { txt: parseNumber(f.txt.value), m: parseNumber(f.m.value), c: parseNumber(f.c.value), recv: parseNumber(f.recv.value || "0") };
    for (const [key, value] of Object.entries(body)) {
      if (Number.isNaN(value)) { showError(`Text Block: ${key} = ${f[key].value} is not a number (H'0500', 0x500 or 1280)`); return; }
    }
    if (f.text.value) body.text = f.text.value;
    else if (f.send.value.trim()) {
      body.send = f.send.value.trim().split(/[\s,]+/).map(parseNumber);
      if (body.send.some(Number.isNaN)) { showError("Text Block: send words are numbers (H'0001' 2 ...)"); return; }
    }
    const started = await command("POST", "/exchanges", body, null, "exchange started");
    if (!started) return;
    show("state", started.state);
    for (let i = 0; i < 100; i += 1) { // bounded: 100 polls, 0.2 s apart
      const ex = await command("GET", `/exchanges/${started.id}`, undefined, null, "exchange");
      if (!ex) return;
      show("state", ex.state);
      if (ex.done) {
        showReport(out, show, ex.result || {});
        return;
      }
      await new Promise((resolve) => setTimeout(resolve, 200));
    }
    show("state", "still running (poll GET /exchanges/" + started.id + ")");
  });
}

// --- trends ---------------------------------------------------------------------------------------

class Ring {
  constructor(size) { this.values = new Float64Array(size); this.size = size; this.start = 0; this.length = 0; }
  push(value) {
    const at = (this.start + this.length) % this.size;
    this.values[at] = value;
    if (this.length < this.size) this.length += 1; else this.start = (this.start + 1) % this.size;
  }
  array() {
    const out = new Array(this.length);
    for (let i = 0; i < this.length; i += 1) out[i] = this.values[(this.start + i) % this.size];
    return out;
  }
  clear() { this.start = 0; this.length = 0; }
}

function catalogue(state) {
  const found = new Map();
  tagSeries(state, found);
  for (const m of state.modules) {
    for (const w of m.iw) found.set(`${m.id}:${w.name}`, { label: `${w.name} (${m.kind})`, get: (s) => signed(s.modules.find((x) => x.id === m.id)?.iw.find((x) => x.name === w.name)?.value) });
    if (m.i_bits !== null) found.set(`${m.id}:I`, { label: `I${m.address} bits`, get: (s) => s.modules.find((x) => x.id === m.id)?.i_bits });
    if (m.o_bits !== null) found.set(`${m.id}:O`, { label: `O${m.address} bits`, get: (s) => s.modules.find((x) => x.id === m.id)?.o_bits });
  }
  for (const t of state.tes) {
    for (const a of t.analog) {
      found.set(`${t.id}:${a.input}:points`, { label: `${t.id} ${a.input} points`, get: (s) => s.tes.find((x) => x.id === t.id)?.analog.find((x) => x.input === a.input)?.points });
      found.set(`${t.id}:${a.input}:${a.unit}`, { label: `${t.id} ${a.input} ${a.unit}`, get: (s) => s.tes.find((x) => x.id === t.id)?.analog.find((x) => x.input === a.input)?.level });
    }
    t.inputs.forEach((_, i) => found.set(`${t.id}:in${i}`, { label: `${t.id} input ${i}`, get: (s) => Number(Boolean(s.tes.find((x) => x.id === t.id)?.inputs[i])) }));
  }
  return found;
}

const trends = {
  series: [], // { key, label, get, ring }
  times: new Ring(TREND_POINTS),
  chart: null,
  follow: true,
  known: null,
  lastDraw: 0,
  sample(state) {
    if (!this.known) {
      this.known = catalogue(state);
      const pick = document.getElementById("trend-pick");
      for (const [key, entry] of this.known) pick.append(el("option", { value: key }, entry.label));
    }
    if (!this.opened) { this.opened = true; openDefaultTrends(this, state); }
    if (!this.series.length || this.filling) return;
    this.times.push(state.clock.t_s);
    for (const s of this.series) {
      const v = s.get(state);
      s.ring.push(v === undefined || v === null ? NaN : Number(v));
    }
    document.getElementById("trend-count").textContent = `${this.times.length} points`;
    const now = performance.now();
    if (now - this.lastDraw > 250) { this.lastDraw = now; this.redraw(); }
  },
  data() {
    return [this.times.array(), ...this.series.map((s) => s.ring.array().map((v) => (Number.isNaN(v) ? null : v)))];
  },
  add(key) {
    if (!this.known || !this.known.has(key) || this.series.some((s) => s.key === key)) return;
    const entry = this.known.get(key);
    const ring = new Ring(TREND_POINTS);
    for (let i = 0; i < this.times.length; i += 1) ring.push(NaN);
    this.series.push({ key, label: entry.label, get: entry.get, ring });
    this.rebuild();
  },
  clear() { this.series = []; this.times.clear(); this.rebuild(); },
  rebuild() {
    const box = document.getElementById("trend-chart");
    if (this.chart) { this.chart.destroy(); this.chart = null; }
    box.textContent = "";
    if (!this.series.length || typeof uPlot === "undefined") return;
    const colours = ["#1b7f3b", "#c0392b", "#2364aa", "#b8860b", "#8e44ad", "#16a085"];
    const width = Math.max(280, box.clientWidth || 600);
    this.chart = new uPlot({
      width, height: 260,
      scales: { x: { time: false } },
      axes: [{ label: "simulated time, s" }, {}],
      series: [{ label: "t s" }, ...this.series.map((s, i) => ({ label: s.label, stroke: colours[i % colours.length], width: 1.5, spanGaps: false }))],
      cursor: { drag: { x: true, y: false } },
      hooks: { setSelect: [(u) => { if (u.select.width > 0) this.follow = false; }] },
    }, this.data(), box);
  },
  redraw() {
    if (!this.chart) return;
    const x = this.chart.scales.x;
    const keep = !this.follow && x.min !== undefined && x.min !== null ? [x.min, x.max] : null;
    this.chart.setData(this.data(), this.follow);
    if (keep) this.chart.setScale("x", { min: keep[0], max: keep[1] });
  },
  view(fn) {
    if (!this.chart) return;
    this.follow = false;
    const { min, max } = this.chart.scales.x;
    const [a, b] = fn(min, max, max - min);
    this.chart.setScale("x", { min: a, max: b });
  },
  csv() {
    const data = this.data();
    const lines = [["t_s", ...this.series.map((s) => `"${s.label.replace(/"/g, "'")}"`)].join(",")];
    for (let i = 0; i < data[0].length; i += 1) lines.push(data.map((col) => (col[i] === null ? "" : col[i])).join(","));
    const blob = new Blob([lines.join("\n") + "\n"], { type: "text/csv" });
    const a = el("a", { href: URL.createObjectURL(blob), download: "fieldtwin-trend.csv" });
    document.body.append(a);
    a.click();
    setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
  },
};

function wireTrends() {
  const get = (id) => document.getElementById(id);
  get("trend-add").addEventListener("click", () => trends.add(get("trend-pick").value));
  get("trend-clear").addEventListener("click", () => trends.clear());
  get("trend-left").addEventListener("click", () => trends.view((a, b, w) => [a - w / 4, b - w / 4]));
  get("trend-right").addEventListener("click", () => trends.view((a, b, w) => [a + w / 4, b + w / 4]));
  get("trend-in").addEventListener("click", () => trends.view((a, b, w) => [a + w / 4, b - w / 4]));
  get("trend-out").addEventListener("click", () => trends.view((a, b, w) => [a - w / 2, b + w / 2]));
  get("trend-live").addEventListener("click", () => { trends.follow = true; trends.redraw(); });
  get("trend-csv").addEventListener("click", () => trends.csv());
}

// --- tags (docs/dashboard.md, "Tags"): labels and values in their units -----------------------------

const TAG_DEVICE_OBJECT = /^(IW|OW|I|O)(\d{1,2}),/; // a module's object: IW5,3 O16,0 I14,0

function tagSource(t) { return t.source || {}; }
function tagDevice(t) { // the device id a tag belongs to ("5", "tes1"), or null for W, B...
  const src = tagSource(t);
  if (src.device) return src.device;
  const m = TAG_DEVICE_OBJECT.exec(src.object || "");
  return m ? m[2] : null;
}
function tagRowHtml(t) {
  const value = t.value === null || t.value === undefined ? "-" : t.text;
  return `<tr data-tag="${esc(t.name)}"><td><b>${esc(t.name)}</b></td><td class="tag-value" data-tag-value="${esc(t.name)}">${esc(value)}</td>
    <td class="muted">${esc(t.source_text)}</td><td class="muted">${esc(t.description || "")}</td></tr>`;
}
function tagNotesHtml(list) { // beside a device's front: its tags, label = value in unit
  if (!list.length) return "";
  return `<div class="tag-notes">${list.map((t) => `<span class="tag-note" data-tag-note="${esc(t.name)}" title="${esc(t.source_text)}: ${esc(t.description || "")}">${esc(t.source_text.replace(/^\S+ (input|output|register) /, "$1 "))} <b>${esc(t.name)}</b> ${esc(t.value === null ? "-" : t.text)}</span>`).join(" · ")}</div>`;
}
const tagView = { section: null, body: null, html: "", notes: new Map() };
function drawTags(state) {
  const tags = (state.tags || []).filter((t) => !t.object);
  if (!tags.length) return;
  if (!tagView.section) {
    tagView.body = el("tbody", {});
    tagView.section = el("section", { id: "tags" }, el("h2", {}, "Tags"),
      el("table", { class: "tags", id: "tag-table" }, el("thead", {}, el("tr", {}, el("th", {}, "tag"), el("th", {}, "value"), el("th", {}, "source"), el("th", {}, "description"))), tagView.body));
    document.getElementById("rack").before(tagView.section);
  }
  const html = tags.map(tagRowHtml).join("");
  if (html !== tagView.html) { tagView.body.innerHTML = html; tagView.html = html; }
  const byDevice = new Map();
  for (const t of tags) {
    const id = tagDevice(t);
    if (id !== null) byDevice.set(id, [...(byDevice.get(id) || []), t]);
  }
  for (const [key, panel] of panels) { // each front's own tags, under its display
    const id = key.slice(key.indexOf(":") + 1);
    const notes = tagNotesHtml(byDevice.get(id) || []);
    let box = tagView.notes.get(key);
    if (!box) { box = el("div", { class: "tag-box" }); panel.display.after(box); tagView.notes.set(key, box); }
    if (box.dataset.html !== notes) { box.innerHTML = notes; box.dataset.html = notes; }
  }
}
function tagSeries(state, found) { // every tag (and default trend object) as a trend series
  for (const t of state.tags || []) {
    const label = t.unit ? `${t.name} (${t.unit})` : t.name;
    found.set(`tag:${t.name}`, { label, tag: t.name, get: (s) => { const v = (s.tags || []).find((x) => x.name === t.name)?.value; return typeof v === "boolean" ? Number(v) : v; } });
  }
}
async function openDefaultTrends(view, state) {
  // the plant file's default trends, with the history the plant kept before the page opened
  const names = (state.trend_defaults || []).filter((n) => view.known && view.known.has(`tag:${n}`));
  if (!names.length) return;
  view.filling = true;
  try {
    const got = await Promise.all(names.map((n) => api("GET", `/trends/${encodeURIComponent(n)}`).catch(() => null)));
    const base = got.find((g) => g && g.points.length)?.points.map((p) => p[0]) || [];
    const cut = base.length ? base[base.length - 1] : -1;
    for (const t of base) view.times.push(t);
    for (let i = 0; i < names.length; i += 1) {
      const key = `tag:${names[i]}`;
      if (view.series.some((s) => s.key === key)) continue;
      const entry = view.known.get(key);
      const ring = new Ring(TREND_POINTS);
      const at = new Map((got[i]?.points || []).filter((p) => p[0] <= cut).map((p) => [p[0], p[1]]));
      for (const t of base) { const v = at.get(t); ring.push(v === undefined || v === null ? NaN : Number(v)); }
      view.series.push({ key, label: entry.label, get: entry.get, ring });
    }
    view.rebuild();
  } finally {
    view.filling = false;
  }
}

// --- traffic ---------------------------------------------------------------------------------------

const traffic = { events: [], held: false, dirty: false };

function matches(e) {
  const get = (id) => document.getElementById(id).value.trim();
  const kind = get("f-kind"), endpoint = get("f-endpoint"), slave = get("f-slave"), fn = get("f-function");
  if (kind && e.kind !== kind) return false;
  if (endpoint && !String(e.endpoint ?? e.device ?? "").includes(endpoint)) return false;
  if (slave && String(e.slave) !== slave) return false;
  if (fn && String(e.function) !== fn && e.function_name !== fn) return false;
  return true;
}
function what(e) {
  if (e.kind === "modbus") {
    const parts = [e.function_name || e.error || ""];
    if (e.address !== undefined) parts.push(`@${e.address}`);
    if (e.count !== undefined) parts.push(`x${e.count}`);
    if (e.exception !== undefined) parts.push(`exception ${e.exception}`);
    parts.push(outcomeText(e));
    parts.push(e.hex || "");
    return parts.filter(Boolean).join(" ");
  }
  if (e.kind === "serial") return `ch ${e.channel} ${JSON.stringify(e.text)}`;
  if (e.kind === "led") return `${e.led} ${e.was} -> ${e.state}`;
  if (e.kind === "clock") return `${e.what}`;
  if (e.kind === "dropped") return `${e.count} events dropped (the page did not keep up)`;
  return JSON.stringify(e);
}
function drawTraffic() {
  traffic.dirty = false;
  const body = document.querySelector("#traffic-table tbody");
  const rows = [];
  for (let i = traffic.events.length - 1; i >= 0 && rows.length < TRAFFIC_SHOWN; i -= 1) {
    const e = traffic.events[i];
    if (!matches(e)) continue;
    rows.push(`<tr class="k-${esc(e.kind)}"><td>${Number(e.t_s).toFixed(3)}</td><td>${esc(e.kind)}</td><td>${esc(e.device)}</td><td>${esc(e.dir ?? "")}</td><td>${esc(what(e))}</td></tr>`);
  }
  body.innerHTML = rows.join("");
  document.getElementById("traffic-count").textContent = `${rows.length} shown of ${traffic.events.length} kept`;
}
function connectEvents(delay = 1000) {
  const url = new URL("/events", location.href);
  url.protocol = location.protocol === "https:" ? "wss:" : "ws:";
  url.searchParams.set("kind", "modbus,serial,led,clock");
  url.searchParams.set("queue", "2000");
  url.searchParams.set("batch", "1"); // each message an array of events, in order
  if (TOKEN) url.searchParams.set("token", TOKEN);
  const ws = new WebSocket(url);
  ws.onmessage = (message) => {
    const batch = JSON.parse(message.data);
    for (const e of Array.isArray(batch) ? batch : [batch]) {
      stats.events += 1;
      if (e.kind === "serial") lastSerial.set(`${e.device} ${e.channel} ${e.dir}`, e.text);
      if (e.kind === "modbus") noteRequest(e);
      traffic.events.push(e);
    }
    if (traffic.events.length > TRAFFIC_KEPT) traffic.events.splice(0, traffic.events.length - TRAFFIC_KEPT);
    traffic.dirty = true;
  };
  ws.onopen = () => { delay = 1000; };
  ws.onclose = () => setTimeout(() => connectEvents(Math.min(delay * 2, 30000)), delay);
}
function wireTraffic() {
  for (const id of ["f-kind", "f-endpoint", "f-slave", "f-function"]) {
    document.getElementById(id).addEventListener("input", drawTraffic);
  }
  const hold = document.getElementById("traffic-pause");
  hold.addEventListener("click", () => { traffic.held = !traffic.held; hold.textContent = traffic.held ? "follow" : "hold"; });
  document.getElementById("traffic-clear").addEventListener("click", () => { traffic.events = []; drawTraffic(); });
  setInterval(() => { if (traffic.dirty && !traffic.held) drawTraffic(); }, 500);
}

// --- views: a silent plant, a removed module, Text Block reports, requests, writes ---------------

let silentSince = null; // wall-clock Date of the first unanswered poll; null while the plant answers
function plantSilent(exc) { // the plant stopped or cannot be reached: nothing on the page is live
  const banner = document.getElementById("plant-down");
  if (silentSince === null) silentSince = new Date();
  const seen = stats.state ? ` The values shown are the last seen, at t = ${stats.state.clock.t_s.toFixed(1)} s.` : "";
  banner.textContent = `The plant does not answer (since ${silentSince.toLocaleTimeString()}: ${exc.message}): it stopped or cannot be reached.${seen}`;
  banner.hidden = false;
  BODY.classList.add("plant-down");
  const mode = document.getElementById("plc-mode");
  mode.textContent = "no answer";
  mode.classList.add("stop");
  stats.down = true;
}
function plantAnswers() {
  if (silentSince === null) return;
  silentSince = null;
  document.getElementById("plant-down").hidden = true;
  BODY.classList.remove("plant-down");
  stats.down = false;
}

function removedModuleHtml(m) { // a slot without its module: no words, no measurements
  const head = `<div class="head"><b>slot ${esc(m.address)}</b> <span class="kind">${esc(m.kind)}</span>
    <span class="state" data-f="state">removed</span></div>`;
  const leds = `<div class="leds">${m.leds.map(([n]) => led(n, "off")).join("")}
    <span class="is">I,S <b data-f="is">${m.is}</b></span></div>`;
  return head + leds + `<div class="removed muted" data-f="removed">module removed from slot ${esc(m.address)}:
    no measurement, no register (I,S = 1 at the PLC); <b>insert module</b> in its controls puts it back</div>`;
}

function hexByte(v) { // H'7A' as the manuals write a report byte, H'0100' for a word
  if (v === null || v === undefined) return "-";
  const n = Number(v) & 0xffff;
  return "H'" + n.toString(16).toUpperCase().padStart(n > 0xff ? 4 : 2, "0") + "'";
}
function printable(hex) { // the data as Latin-1 text, "·" for a byte that is not printable
  const bytes = (String(hex || "").match(/../g) || []).map((b) => parseInt(b, 16));
  if (!bytes.some((b) => b >= 0x20 && b < 0x7f)) return "";
  return bytes.map((b) => (b >= 0x20 && b < 0x7f) || b >= 0xa0 ? String.fromCharCode(b) : "·").join("");
}
function showReport(out, show, r) { // a finished exchange: V (or R) in hex, the data in hex and as text
  const name = r.R !== undefined ? "R" : "V";
  out.querySelector('[data-f="V"]').previousElementSibling.textContent = name;
  show("V", r[name] === undefined ? "-" : `${hexByte(r[name])} (${r[name]})`);
  show("S", r.S ?? "-"); show("E", r.E ?? "-"); show("error", r.error || "-");
  show("words", (r.words || []).map((w) => "H'" + w.toString(16).toUpperCase().padStart(4, "0") + "'").join(" ") || "-");
  show("data", (String(r.data || "").match(/../g) || []).join(" ").toUpperCase() || "-");
  const text = printable(r.data);
  show("text", text ? JSON.stringify(text) : "-");
}

const lastRequest = new Map(); // "endpoint TES name" -> the newest request that TES met and its outcome
function noteRequest(e) { // the outcome per TES is the event's own (the trace's `tes`), by TES name
  if (e.fault !== undefined || e.error !== undefined) return;
  if (e.dir === "in") {
    const what = [e.function_name, e.address !== undefined ? `@${e.address}` : "", e.count !== undefined ? `x${e.count}` : ""].filter(Boolean).join(" ");
    for (const [name, outcome] of Object.entries(e.tes || {})) {
      if (outcome === "not_addressed") continue; // a request for another slave is not this TES's
      const key = `${e.endpoint} ${name}`;
      lastRequest.delete(key); // re-inserted last: the map's order is the age, the oldest goes first
      lastRequest.set(key, { t_s: e.t_s, what, outcome, reply: null });
    }
    if (e.rejected !== undefined) lastRequest.set(`${e.endpoint} #${e.slave}`, { t_s: e.t_s, what, outcome: `rejected: exception ${e.rejected}`, reply: null });
    while (lastRequest.size > 1000) lastRequest.delete(lastRequest.keys().next().value);
  } else if (e.from && lastRequest.has(`${e.endpoint} ${e.from}`)) {
    lastRequest.get(`${e.endpoint} ${e.from}`).reply = e.exception !== undefined ? `exception ${e.exception}` : "answered";
  }
}
function lastRequestHtml(t) { // on a TES's front: the newest request it met and what it did with it
  const r = lastRequest.get(`${t.endpoint} ${t.kind} #${t.slave}`) || lastRequest.get(`${t.endpoint} #${t.slave}`);
  if (!r) return `<div class="lastreq muted" data-f="last-request">no request seen since the page opened</div>`;
  const bad = !/^answers|^broadcast$/.test(r.outcome);
  return `<div class="lastreq" data-f="last-request">last request <span class="muted">t = ${Number(r.t_s).toFixed(3)} s</span>
    ${esc(r.what)} · <b class="${bad ? "alarm" : ""}" data-f="outcome">${esc(r.outcome)}</b>${r.reply ? ` · ${esc(r.reply)}` : ""}</div>`;
}
function outcomeText(e) { // "-> TES 8EA #2 no_answer": what each addressed TES did with a request
  if (e.dir !== "in" || !e.tes) return "";
  const told = Object.entries(e.tes).filter(([, what]) => what !== "not_addressed");
  return told.length ? "→ " + told.map(([name, what]) => `${name} ${what}`).join("; ") : "→ no TES addressed";
}

function writeObjectRow(kind, dev, base, msg) { // write a PL7 object or a TES register, read it back
  if (kind !== "tes" && kind !== "module") return "";
  const example = kind === "tes" ? "H'014' or filter_0" : `OW${dev.address},1 or O${dev.address},0`;
  const name = el("input", { class: "obj-name", size: "10", placeholder: example });
  const value = el("input", { class: "obj-value", size: "7", placeholder: "H'00FF'" });
  const shown = el("code", { class: "obj-read" });
  const write = async () => {
    const object = name.value.trim(), number = parseNumber(value.value);
    if (!object) { showError(`write: name the ${kind === "tes" ? "register" : "object"} (${example})`, msg); return; }
    if (Number.isNaN(number) || number < 0 || number > 0xffff) { showError(`write ${object}: ${value.value} is not a value 0..65535 (H'00FF', 0x00FF or 255)`, msg); return; }
    const path = `${base}/objects/${encodeURIComponent(object)}`;
    if (!await command("PUT", path, { value: number }, msg, `${object} written`)) return;
    const back = await command("GET", `${path}?peek=true`, undefined, null, "");
    if (back) shown.textContent = `${object} = ${back.hex}`;
  };
  return el("div", { class: "write-row" }, el("span", { class: "lbl" }, kind === "tes" ? "register" : "object"), name,
    value, el("button", { type: "button", class: "write", onclick: write }, "write"), shown);
}

window.__fieldtwinTrends = trends;
wireHeader();
wireTextBlock();
wireTrends();
wireTraffic();
connectEvents();
startPolling();
