// Makes a report's line charts zoom and read out (see plsa::report::chartScript).
// Embedded into the page at build time; the charts are complete without it.
(function () {
  'use strict';
  var NS = 'http://www.w3.org/2000/svg';
  function el(name, attrs, parent) {
    var e = document.createElementNS(NS, name);
    for (var k in attrs) e.setAttribute(k, attrs[k]);
    if (parent) parent.appendChild(e);
    return e;
  }
  function niceStep(span, n) {
    var raw = span / Math.max(1, n), mag = Math.pow(10, Math.floor(Math.log10(raw)));
    var steps = [1, 2, 5, 10];
    for (var i = 0; i < steps.length; ++i) if (steps[i] * mag >= raw) return steps[i] * mag;
    return 10 * mag;
  }
  function fmt(v) { return v === null ? 'n/a' : String(Number(v.toPrecision(4)) + 0); }
  function lowerBound(x, v) {
    var lo = 0, hi = x.length;
    while (lo < hi) { var m = (lo + hi) >> 1; if (x[m] < v) lo = m + 1; else hi = m; }
    return lo;
  }
  var uid = 0;

  function Plot(div, data) {
    var svg = div.querySelector('svg.zoomable');
    var g = svg.getAttribute('data-plot').split(' ').map(Number);
    this.div = div; this.svg = svg; this.x = data.x; this.labels = data.labels; this.ys = data.series;
    this.left = g[0]; this.top = g[1]; this.w = g[2]; this.h = g[3];
    this.link = div.getAttribute('data-x-label');
    this.full = [this.x[0], this.x[this.x.length - 1]];
    this.view = this.full.slice();
    this.paths = svg.querySelectorAll('g.traces path.series');
    var clip = 'plsa-clip-' + (++uid);
    var defs = el('defs', {}, svg);
    el('rect', {x: this.left, y: this.top, width: this.w, height: this.h}, el('clipPath', {id: clip}, defs));
    svg.querySelector('g.traces').setAttribute('clip-path', 'url(#' + clip + ')');
    this.cursor = el('line', {'class': 'cursor', y1: this.top, y2: this.top + this.h, stroke: '#888',
                              'stroke-dasharray': '2,2', visibility: 'hidden'}, svg);
    this.band = el('rect', {'class': 'zoom-band', y: this.top, height: this.h, fill: '#4060c0',
                            'fill-opacity': 0.15, visibility: 'hidden'}, svg);
    this.readout = el('g', {'class': 'readout', 'font-size': 11, visibility: 'hidden'}, svg);
    var y0 = this.top + 14 + 18 * this.labels.length + 10;
    for (var i = 0; i <= this.labels.length; ++i)
      el('text', {x: this.left + this.w + 10, y: y0 + 14 * i}, this.readout);
  }

  // Redraw the lines, the y range and the ticks for the x span [a, b].
  Plot.prototype.show = function (a, b) {
    var x = this.x, i0 = Math.max(0, lowerBound(x, a) - 1), i1 = Math.min(x.length, lowerBound(x, b) + 1);
    var lo = Infinity, hi = -Infinity;
    this.ys.forEach(function (y) {
      for (var i = i0; i < i1; ++i) if (y[i] !== null) { lo = Math.min(lo, y[i]); hi = Math.max(hi, y[i]); }
    });
    if (!isFinite(lo)) { lo = 0; hi = 1; }
    if (hi - lo < 1e-12) { lo -= 1; hi += 1; }
    var pad = 0.05 * (hi - lo);
    this.view = [a, b]; this.yr = [lo - pad, hi + pad];
    var self = this;
    this.ys.forEach(function (y, s) { self.paths[s].setAttribute('d', self.trace(y, i0, i1)); });
    this.ticks();
  };
  Plot.prototype.X = function (v) { return this.left + (v - this.view[0]) / Math.max(1e-12, this.view[1] - this.view[0]) * this.w; };
  Plot.prototype.Y = function (v) { return this.top + (this.yr[1] - v) / (this.yr[1] - this.yr[0]) * this.h; };

  // A path through samples i0..i1 that keeps, in each run of samples one pixel
  // column wide, the first, lowest, highest and last point; null breaks the line.
  Plot.prototype.trace = function (y, i0, i1) {
    var d = [], pen = false, per = Math.max(1, Math.floor((i1 - i0) / (2 * this.w))), self = this, keep = [];
    function flush() {
      keep.sort(function (p, q) { return p - q; }).forEach(function (i, k) {
        if (k > 0 && i === keep[k - 1]) return;
        d.push((pen ? 'L' : 'M') + self.X(self.x[i]).toFixed(2) + ',' + self.Y(y[i]).toFixed(2));
        pen = true;
      });
      keep = [];
    }
    for (var s = i0; s < i1; s += per) {
      var lo = -1, hi = -1;
      for (var i = s; i < Math.min(i1, s + per); ++i) {
        if (y[i] === null) { if (lo >= 0) keep.push(lo, hi); flush(); pen = false; lo = hi = -1; continue; }
        if (lo < 0) keep.push(i);
        if (lo < 0 || y[i] < y[lo]) lo = i;
        if (hi < 0 || y[i] > y[hi]) hi = i;
        if (i + 1 === Math.min(i1, s + per)) keep.push(i);
      }
      if (lo >= 0) keep.push(lo, hi);
      flush();
    }
    return d.join(' ');
  };

  Plot.prototype.ticks = function () {
    var gy = this.svg.querySelector('g.y-ticks'), gx = this.svg.querySelector('g.x-ticks');
    gy.textContent = ''; gx.textContent = '';
    var ys = niceStep(this.yr[1] - this.yr[0], 5);
    for (var v = Math.ceil(this.yr[0] / ys) * ys; v <= this.yr[1]; v += ys) {
      var y = this.Y(v);
      el('line', {x1: this.left, x2: this.left + this.w, y1: y, y2: y, stroke: '#e3e3e3'}, gy);
      el('text', {x: this.left - 6, y: y + 4, 'font-size': 11, 'text-anchor': 'end'}, gy).textContent = fmt(v);
    }
    var xs = niceStep(this.view[1] - this.view[0], 8);
    for (var u = Math.ceil(this.view[0] / xs) * xs; u <= this.view[1]; u += xs)
      el('text', {x: this.X(u), y: this.top + this.h + 15, 'font-size': 11, 'text-anchor': 'middle'}, gx)
        .textContent = fmt(u);
  };

  // The x value under an event, or null outside the plot area.
  Plot.prototype.at = function (ev) {
    var p = this.svg.createSVGPoint();
    p.x = ev.clientX; p.y = ev.clientY;
    p = p.matrixTransform(this.svg.getScreenCTM().inverse());
    if (p.x < this.left || p.x > this.left + this.w || p.y < this.top || p.y > this.top + this.h) return null;
    return this.view[0] + (p.x - this.left) / this.w * (this.view[1] - this.view[0]);
  };

  Plot.prototype.hover = function (v) {
    if (v === null) { this.cursor.setAttribute('visibility', 'hidden'); this.readout.setAttribute('visibility', 'hidden'); return; }
    var x = this.x, i = Math.min(x.length - 1, lowerBound(x, v));
    if (i > 0 && v - x[i - 1] < x[i] - v) --i;
    var px = this.X(x[i]), lines = this.readout.childNodes, self = this;
    this.cursor.setAttribute('x1', px); this.cursor.setAttribute('x2', px);
    lines[0].textContent = this.link + ': ' + fmt(x[i]);
    this.labels.forEach(function (l, s) { lines[s + 1].textContent = l + ': ' + fmt(self.ys[s][i]); });
    this.cursor.setAttribute('visibility', 'visible'); this.readout.setAttribute('visibility', 'visible');
  };

  var plots = [];
  Array.prototype.forEach.call(document.querySelectorAll('div.plot'), function (d) {
    var data = JSON.parse(d.querySelector('script.plot-data').textContent);
    if (data.x.length > 1) plots.push(new Plot(d, data));
  });
  function linked(p) { return plots.filter(function (q) { return q.link === p.link; }); }

  plots.forEach(function (p) {
    var start = null;
    p.svg.addEventListener('mousedown', function (ev) { start = p.at(ev); if (start !== null) ev.preventDefault(); });
    p.svg.addEventListener('mousemove', function (ev) {
      var v = p.at(ev);
      p.hover(v);
      if (start === null || v === null) return;
      var a = p.X(Math.min(start, v)), b = p.X(Math.max(start, v));
      p.band.setAttribute('x', a); p.band.setAttribute('width', b - a); p.band.setAttribute('visibility', 'visible');
    });
    p.svg.addEventListener('mouseleave', function () { p.hover(null); });
    p.svg.addEventListener('mouseup', function (ev) {
      var v = p.at(ev), s = start;
      start = null; p.band.setAttribute('visibility', 'hidden');
      if (s === null || v === null || Math.abs(p.X(v) - p.X(s)) < 4) return;
      linked(p).forEach(function (q) { q.show(Math.min(s, v), Math.max(s, v)); });
    });
    p.svg.addEventListener('dblclick', function () {
      linked(p).forEach(function (q) { q.show(q.full[0], q.full[1]); });
    });
  });
})();
