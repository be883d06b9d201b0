/* tdf report loss plot: every loss term against the iteration on a log scale, drawn on a canvas
 * from the run's records (inline JSON), with a legend whose checkboxes hide terms and a readout
 * of the values under the mouse. Classic script, works from file://.
 *
 * Markup (written by tdf's report module):
 *   <div class="tdf-plot" data-source="ID-of-a-script-type-application/json" data-boundary="150">
 *     <canvas width=W height=H></canvas><div class="tdf-plot-legend"></div>
 *     <div class="tdf-plot-readout"></div>
 *   </div>
 * The JSON is an array of {"iteration": i, "seconds": s, "<term>": value, ...}.
 * Sets data-state="ready" once drawn (or "empty" without data). */
(function () {
  'use strict';
  var kColours = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#7f7f7f',
                  '#bcbd22', '#17becf'];

  function start(container) {
    var source = document.getElementById(container.getAttribute('data-source'));
    var records = source ? JSON.parse(source.textContent) : [];
    var boundary = Number(container.getAttribute('data-boundary') || 0);
    var canvas = container.querySelector('canvas');
    var legend = container.querySelector('.tdf-plot-legend');
    var readout = container.querySelector('.tdf-plot-readout');
    var terms = [];
    records.forEach(function (r) {
      Object.keys(r).forEach(function (k) {
        if (k !== 'iteration' && k !== 'seconds' && terms.indexOf(k) < 0) terms.push(k);
      });
    });
    if (!records.length || !terms.length) {
      container.setAttribute('data-state', 'empty');
      readout.textContent = 'no loss records';
      return;
    }
    var shown = {};
    terms.forEach(function (t, i) {
      shown[t] = true;
      var label = document.createElement('label');
      var box = document.createElement('input');
      box.type = 'checkbox';
      box.checked = true;
      box.addEventListener('change', function () { shown[t] = box.checked; draw(); });
      var swatch = document.createElement('span');
      swatch.className = 'swatch';
      swatch.style.background = kColours[i % kColours.length];
      label.appendChild(box);
      label.appendChild(swatch);
      label.appendChild(document.createTextNode(t));
      legend.appendChild(label);
    });

    var ctx = canvas.getContext('2d');
    var W = canvas.width, H = canvas.height;
    var left = 64, right = 16, top = 12, bottom = 40;
    var x0 = records[0].iteration, x1 = records[records.length - 1].iteration;
    if (x1 === x0) x1 = x0 + 1;
    var scale = {};

    function range() {
      var lo = Infinity, hi = -Infinity;
      records.forEach(function (r) {
        terms.forEach(function (t) {
          var v = r[t];
          if (shown[t] && typeof v === 'number' && v > 0 && isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
        });
      });
      if (!isFinite(lo)) { lo = 1e-3; hi = 1; }
      scale.lo = Math.floor(Math.log10(lo));
      scale.hi = Math.ceil(Math.log10(hi));
      if (scale.hi === scale.lo) scale.hi = scale.lo + 1;
    }
    function px(iteration) { return left + (iteration - x0) / (x1 - x0) * (W - left - right); }
    function py(value) {
      return top + (scale.hi - Math.log10(value)) / (scale.hi - scale.lo) * (H - top - bottom);
    }

    function draw(mouseIteration) {
      range();
      ctx.clearRect(0, 0, W, H);
      ctx.fillStyle = '#ffffff';
      ctx.fillRect(0, 0, W, H);
      ctx.font = '11px sans-serif';
      ctx.strokeStyle = '#e3e7eb';
      ctx.fillStyle = '#5f6b76';
      ctx.lineWidth = 1;
      for (var e = scale.lo; e <= scale.hi; ++e) {
        var y = py(Math.pow(10, e));
        ctx.beginPath(); ctx.moveTo(left, y); ctx.lineTo(W - right, y); ctx.stroke();
        ctx.textAlign = 'right'; ctx.textBaseline = 'middle';
        ctx.fillText('1e' + e, left - 6, y);
      }
      var step = Math.max(1, Math.pow(10, Math.floor(Math.log10((x1 - x0) / 4 || 1))));
      ctx.textAlign = 'center'; ctx.textBaseline = 'top';
      for (var it = Math.ceil(x0 / step) * step; it <= x1; it += step) ctx.fillText(String(it), px(it), H - bottom + 6);
      ctx.fillText('iteration', left + (W - left - right) / 2, H - 16);
      if (boundary > x0 && boundary <= x1) {
        ctx.setLineDash([4, 4]); ctx.strokeStyle = '#888';
        ctx.beginPath(); ctx.moveTo(px(boundary), top); ctx.lineTo(px(boundary), H - bottom); ctx.stroke();
        ctx.setLineDash([]);
        ctx.textAlign = 'left'; ctx.fillText('refinement', px(boundary) + 4, top);
      }
      terms.forEach(function (t, i) {
        if (!shown[t]) return;
        ctx.strokeStyle = kColours[i % kColours.length];
        ctx.lineWidth = t === 'total' ? 2 : 1.25;
        ctx.beginPath();
        var pen = false;
        records.forEach(function (r) {
          var v = r[t];
          if (typeof v !== 'number' || !(v > 0) || !isFinite(v)) { pen = false; return; }
          var x = px(r.iteration), y = py(v);
          if (pen) ctx.lineTo(x, y); else ctx.moveTo(x, y);
          pen = true;
        });
        ctx.stroke();
      });
      if (mouseIteration !== undefined) {
        ctx.strokeStyle = '#333'; ctx.lineWidth = 1;
        ctx.beginPath(); ctx.moveTo(px(mouseIteration), top); ctx.lineTo(px(mouseIteration), H - bottom); ctx.stroke();
      }
    }

    canvas.addEventListener('mousemove', function (event) {
      var rect = canvas.getBoundingClientRect();
      var x = (event.clientX - rect.left) * (W / rect.width);
      var target = x0 + (x - left) / (W - left - right) * (x1 - x0);
      var best = records[0];
      records.forEach(function (r) { if (Math.abs(r.iteration - target) < Math.abs(best.iteration - target)) best = r; });
      draw(best.iteration);
      readout.textContent = 'iteration ' + best.iteration + ': ' + terms.filter(function (t) {
        return typeof best[t] === 'number';
      }).map(function (t) { return t + ' ' + best[t].toPrecision(4); }).join(', ');
    });
    canvas.addEventListener('mouseleave', function () { draw(); readout.textContent = ''; });
    draw();
    readout.textContent = 'move the mouse over the plot for the values; untick a term to hide it';
    container.setAttribute('data-state', 'ready');
  }

  window.tdfStartPlots = function () {
    var containers = document.querySelectorAll('.tdf-plot');
    for (var i = 0; i < containers.length; ++i) start(containers[i]);
  };
})();
