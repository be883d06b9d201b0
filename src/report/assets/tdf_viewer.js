/* tdf report viewer: shows an exported .glb with three.js (classic scripts, so the page works
 * from file://, where Chromium refuses ES modules and fetch()). The model arrives as base64 in a
 * <script> beside the page (tdfModels[id]) and is parsed in memory; nothing is fetched.
 *
 * Markup (written by tdf's report module):
 *   <div class="tdf-viewer" data-model="ID" data-camera='{"position":[x,y,z],"target":[x,y,z],
 *        "fovy":50,"near":0.01,"far":100}'>
 *     <canvas width=W height=H></canvas> <div class="tdf-viewer-status"></div> <controls...>
 *   </div>
 * Sets data-state on the container: "loading", then "ready" after the first frame with the
 * model, "error" or "unavailable" (with a message in the status line). */
(function () {
  'use strict';

  function base64ToArrayBuffer(text) {
    var binary = atob(text);
    var bytes = new Uint8Array(binary.length);
    for (var i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
    return bytes.buffer;
  }

  function setState(container, state, message) {
    container.setAttribute('data-state', state);
    var status = container.querySelector('.tdf-viewer-status');
    if (status) status.textContent = message || '';
  }

  function webglAvailable() {
    try {
      var c = document.createElement('canvas');
      return !!(window.WebGLRenderingContext && (c.getContext('webgl2') || c.getContext('webgl')));
    } catch (e) {
      return false;
    }
  }

  function start(container) {
    var id = container.getAttribute('data-model');
    var models = window.tdfModels || {};
    if (typeof THREE === 'undefined' || !THREE.GLTFLoader || !THREE.OrbitControls) {
      setState(container, 'unavailable', '3D view unavailable: three.js was not installed when this report was ' +
        'written (scripts/install-deps.sh installs it).');
      return;
    }
    if (!models[id]) {
      setState(container, 'unavailable', '3D view unavailable: the model script ' + id + ' did not load.');
      return;
    }
    if (!webglAvailable()) {
      setState(container, 'unavailable', '3D view unavailable: this browser has no WebGL.');
      return;
    }
    var spec = JSON.parse(container.getAttribute('data-camera'));
    var canvas = container.querySelector('canvas');
    var renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: true, preserveDrawingBuffer: true});
    renderer.setPixelRatio(1);
    renderer.setSize(canvas.width, canvas.height, false);
    renderer.outputEncoding = THREE.sRGBEncoding;
    renderer.setClearColor(new THREE.Color(spec.background || '#30343a'), 1);

    var scene = new THREE.Scene();
    var camera = new THREE.PerspectiveCamera(spec.fovy, canvas.width / canvas.height, spec.near, spec.far);
    var target = new THREE.Vector3().fromArray(spec.target);
    var home = new THREE.Vector3().fromArray(spec.position);
    camera.position.copy(home);
    camera.up.set(0, 1, 0);
    camera.lookAt(target);

    var ambient = new THREE.AmbientLight(0xffffff, 0.25);
    var sun = new THREE.DirectionalLight(0xffffff, 2.2);
    scene.add(ambient, sun, sun.target);

    var controls = new THREE.OrbitControls(camera, canvas);
    controls.target.copy(target);
    controls.enableDamping = false;
    controls.update();

    var lightAzimuth = container.querySelector('[data-control=light-azimuth]');
    var lightElevation = container.querySelector('[data-control=light-elevation]');
    var normalToggle = container.querySelector('[data-control=normal-map]');
    var resetButton = container.querySelector('[data-control=reset]');
    var backgroundInput = container.querySelector('[data-control=background]');
    var materials = [];

    // The light is given relative to the camera (azimuth right of the view direction, elevation
    // above it), so it stays where the user put it while orbiting.
    function placeLight() {
      var az = THREE.MathUtils.degToRad(lightAzimuth ? Number(lightAzimuth.value) : 35);
      var el = THREE.MathUtils.degToRad(lightElevation ? Number(lightElevation.value) : 25);
      var local = new THREE.Vector3(Math.sin(az) * Math.cos(el), Math.sin(el), Math.cos(az) * Math.cos(el));
      local.applyQuaternion(camera.quaternion);
      sun.position.copy(controls.target).add(local.multiplyScalar(10));
      sun.target.position.copy(controls.target);
    }

    function render() {
      placeLight();
      renderer.render(scene, camera);
    }

    controls.addEventListener('change', render);
    if (lightAzimuth) lightAzimuth.addEventListener('input', render);
    if (lightElevation) lightElevation.addEventListener('input', render);
    if (normalToggle) {
      normalToggle.addEventListener('change', function () {
        materials.forEach(function (m) {
          m.normalMap = normalToggle.checked ? m.userData.tdfNormalMap : null;
          m.needsUpdate = true;
        });
        render();
      });
    }
    if (backgroundInput) {
      backgroundInput.addEventListener('input', function () {
        renderer.setClearColor(new THREE.Color(backgroundInput.value), 1);
        render();
      });
    }
    if (resetButton) {
      resetButton.addEventListener('click', function () {
        controls.target.copy(target);
        camera.position.copy(home);
        camera.lookAt(target);
        controls.update();
        render();
      });
    }

    setState(container, 'loading', 'loading the model...');
    var loader = new THREE.GLTFLoader();
    loader.parse(base64ToArrayBuffer(models[id]), '', function (gltf) {
      gltf.scene.traverse(function (node) {
        if (!node.isMesh) return;
        var list = Array.isArray(node.material) ? node.material : [node.material];
        list.forEach(function (m) {
          m.userData.tdfNormalMap = m.normalMap || null;
          // The maps carry the whole appearance: no metal, fully rough (Lambert-like, as tdf's renders).
          if ('metalness' in m) m.metalness = 0;
          if ('roughness' in m) m.roughness = 1;
          materials.push(m);
        });
      });
      scene.add(gltf.scene);
      var withNormals = materials.filter(function (m) { return m.normalMap; }).length;
      render();
      setState(container, 'ready', 'drag: orbit, wheel: zoom, right-drag: pan' +
        (withNormals ? '' : ' (this model has no normal map)'));
    }, function (error) {
      setState(container, 'error', 'could not read the model: ' + (error && error.message ? error.message : error));
    });
  }

  window.tdfStartViewers = function () {
    var containers = document.querySelectorAll('.tdf-viewer');
    for (var i = 0; i < containers.length; ++i) start(containers[i]);
  };
})();
