/* visviva web viewer: plays the animation embedded in this page (the JSON element
 * #visviva-data, written by visviva.viz.viewer.write_viewer) with three.js (global THREE).
 *
 * Frame k of the page shows recorded frame times[k]; playback picks the frame from the
 * elapsed wall-clock time (k = floor(elapsed * fps * speed)), never by counting redraws, so it
 * runs in real time however fast the machine draws. Y is up, lengths in metres.
 *
 * Each kind of geometry is one entry of LAYERS (points, edges, faces, bodies, scenery): a
 * builder that adds its objects to the scene and returns an update() called after every frame
 * change. A recording of rigid bodies alone has no points layer.
 *
 * Points that are born and die come with per-frame alive bits (and, with a trail, birth bits),
 * radii and colours when the recording has them: a frame draws only its live points, at that
 * frame's radius and colour, and a trail starts at its point's birth.
 */
(async function () {
  "use strict";

  // A failure (no WebGL, corrupt data) is shown on the page, not only in the console.
  function fail(message) {
    const box = document.getElementById("failure");
    box.textContent = "The viewer could not start: " + message;
    box.style.display = "block";
  }
  window.addEventListener("error", (event) => fail(event.message));
  window.addEventListener("unhandledrejection", (event) => fail(String(event.reason)));

  const BACKGROUND = 0xeef1f5;
  const POINT_COLOUR = 0x2f6fb3;
  const NIGHT = 0x03050c; // a star field's sky
  const STAR_COLOUR = 0xffe6c7; // a star's colour when the recording gives none
  const EDGE_COLOUR = 0x1d2733;
  const FACE_COLOUR = 0xd9822b;
  const FIELD_OF_VIEW = 45; // degrees, vertical
  const FRAMING_MARGIN = 1.15; // camera distance over the distance that just fits the scene
  const ORBIT_RATE = 2 * Math.PI; // radians per canvas height dragged
  const ZOOM_RATE = 0.0015; // log-distance per wheel delta unit
  // A sphere of n segments around and n/2 + 1 rings has n² triangles (minus n at the poles);
  // ~150k in all keeps software WebGL (SwiftShader, 2 cores) near 8 frames/s with 4096 points.
  const SPHERE_SEGMENTS = [24, 16, 12, 8, 6, 4];
  const SPHERE_TRIANGLE_BUDGET = 150000;
  const POLAR_LIMIT = 0.01; // radians kept from the poles, where "up" is undefined

  function base64Bytes(text) {
    if (typeof Uint8Array.fromBase64 === "function") return Uint8Array.fromBase64(text);
    const raw = atob(text);
    const bytes = new Uint8Array(raw.length);
    for (let i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
    return bytes;
  }

  /* Base64 text of little-endian binary -> typed array (typed arrays use the host's byte
   * order, little-endian on every platform browsers run on in practice). */
  function decode(text, Type) {
    const bytes = base64Bytes(text);
    return new Type(bytes.buffer, bytes.byteOffset, bytes.byteLength / Type.BYTES_PER_ELEMENT);
  }

  /* Base64 text of a zlib stream -> its inflated bytes (the browser's DecompressionStream). */
  async function inflate(text) {
    const stream = new Blob([base64Bytes(text)])
      .stream().pipeThrough(new DecompressionStream("deflate"));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }

  /* Quantized positions (see _payload.py) -> Float32Array (frames, P, 3) [m]: inflate the
   * zlib stream, join the low- and high-byte planes, add up the frame differences (Uint16Array
   * arithmetic wraps modulo 2^16, as the encoder's differences do) and scale onto the grid. */
  async function decodePositions(layer, frameCount, stride) {
    const planes = await inflate(layer.positions);
    const n = frameCount * stride;
    if (planes.length !== 2 * n) throw new Error("corrupt position data");
    const positions = new Float32Array(n);
    const level = new Uint16Array(stride);
    const [ox, oy, oz] = layer.origin;
    const [sx, sy, sz] = layer.step;
    for (let k = 0, i = 0; k < frameCount; k++) {
      for (let j = 0; j < stride; j += 3, i += 3) {
        level[j] += planes[i] | (planes[n + i] << 8);
        level[j + 1] += planes[i + 1] | (planes[n + i + 1] << 8);
        level[j + 2] += planes[i + 2] | (planes[n + i + 2] << 8);
        positions[i] = ox + level[j] * sx;
        positions[i + 1] = oy + level[j + 1] * sy;
        positions[i + 2] = oz + level[j + 2] * sz;
      }
    }
    return positions;
  }

  /* Radii that change: 16-bit levels in frame differences -> Float32Array (frames, P) [m]. */
  async function decodeRadii(radii, frameCount, count) {
    const planes = await inflate(radii.data);
    const n = frameCount * count;
    if (planes.length !== 2 * n) throw new Error("corrupt radius data");
    const out = new Float32Array(n);
    const level = new Uint16Array(count);
    for (let i = 0; i < n; i++) {
      level[i % count] += planes[i] | (planes[n + i] << 8);
      out[i] = level[i % count] * radii.step;
    }
    return out;
  }

  /* Colours that change: 8-bit sRGB frame differences -> Uint8Array (frames, P, 3). */
  async function decodeFrameColours(text, frameCount, count) {
    const rgb = await inflate(text);
    const stride = 3 * count;
    if (rgb.length !== frameCount * stride) throw new Error("corrupt colour data");
    for (let i = stride; i < rgb.length; i++) rgb[i] += rgb[i - stride]; // wraps modulo 256
    return rgb;
  }

  /* Bits, one per point per frame (little-endian bit order) -> Uint8Array (frames, P) of 0/1;
   * with xor, each frame's bits are its changes from the previous frame. */
  async function decodeBits(text, frameCount, count, xor) {
    const bytes = await inflate(text);
    const n = frameCount * count;
    if (bytes.length !== Math.ceil(n / 8)) throw new Error("corrupt alive data");
    const bits = new Uint8Array(n);
    for (let i = 0; i < n; i++) {
      bits[i] = (bytes[i >> 3] >> (i & 7)) & 1;
      if (xor && i >= count) bits[i] ^= bits[i - count];
    }
    return bits;
  }

  const data = JSON.parse(document.getElementById("visviva-data").textContent);
  const frames = data.frames;
  const fps = data.fps;
  const times = decode(data.times, Float64Array);
  const pointData = data.layers.points || { count: 0 }; // none with rigid bodies alone
  const pointCount = pointData.count;
  const stride = pointCount * 3;
  const allPositions = pointCount ? await decodePositions(pointData, frames, stride)
    : new Float32Array(0); // (frames, P, 3) [m]
  // Present only for points that are born and die, or whose radii or colours change.
  const alive = pointData.alive ? await decodeBits(pointData.alive, frames, pointCount, true)
    : null; // (frames, P) 0/1
  const births = pointData.births
    ? await decodeBits(pointData.births, frames, pointCount, false) : null;
  const frameRadii = pointData.radii ? await decodeRadii(pointData.radii, frames, pointCount)
    : null; // (frames, P) [m]
  const frameColours = pointData.frame_colors
    ? await decodeFrameColours(pointData.frame_colors, frames, pointCount) : null;

  const low = new THREE.Vector3().fromArray(data.bounds[0]);
  const high = new THREE.Vector3().fromArray(data.bounds[1]);
  const centre = low.clone().add(high).multiplyScalar(0.5);
  const diagonal = high.clone().sub(low).length();
  const size = diagonal > 0 ? diagonal : 1; // [m] scale of grid, camera and zoom limits

  const canvas = document.getElementById("view");
  const renderer = new THREE.WebGLRenderer({
    canvas, antialias: true, preserveDrawingBuffer: true, powerPreference: "high-performance",
  });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(BACKGROUND);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8d8a80, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.copy(centre).add(new THREE.Vector3(0.5, 1.0, 0.7).multiplyScalar(size));
  sun.target.position.copy(centre);
  scene.add(sun, sun.target);

  /* The current frame's positions, shared by every layer that draws through point indices. */
  const current = new THREE.BufferAttribute(new Float32Array(stride), 3);
  current.setUsage(THREE.DynamicDrawUsage);
  function loadFrame(k) {
    current.array.set(allPositions.subarray(k * stride, (k + 1) * stride));
    current.needsUpdate = true;
  }

  /* Colour i of 8-bit sRGB triples (setHex reads sRGB, as the recording's colours are). */
  function srgb(rgb, i, target = new THREE.Color()) {
    return target.setHex((rgb[3 * i] << 16) | (rgb[3 * i + 1] << 8) | rgb[3 * i + 2]);
  }

  /* The 8-bit sRGB colours of frame k's points, or null for the default colour. */
  function coloursAt(k, staticRgb) {
    if (frameColours) return frameColours.subarray(3 * pointCount * k, 3 * pointCount * (k + 1));
    return staticRgb;
  }

  /* Each point's path over the last layer.trail frames: one polyline per point (segments
   * j, j+1), paler than the point, refilled from the decoded positions when the frame changes.
   * A point that is born starts a new path: a reused slot never joins two lives. */
  function trailLines(layer) {
    const length = layer.trail + 1;
    const rgb = layer.colors ? decode(layer.colors, Uint8Array) : null;
    const chain = new Uint32Array(2 * (length - 1));
    for (let j = 0; j < length - 1; j++) { chain[2 * j] = j; chain[2 * j + 1] = j + 1; }
    const lines = [];
    const materials = [];
    const background = new THREE.Color(BACKGROUND);
    for (let i = 0; i < pointCount; i++) {
      const geometry = new THREE.BufferGeometry();
      const path = new THREE.BufferAttribute(new Float32Array(3 * length), 3);
      path.setUsage(THREE.DynamicDrawUsage);
      geometry.setAttribute("position", path);
      geometry.setIndex(new THREE.BufferAttribute(chain, 1));
      const colour = rgb ? srgb(rgb, i) : new THREE.Color(POINT_COLOUR);
      colour.lerp(background, 0.4);
      const material = new THREE.LineBasicMaterial({ color: colour });
      const line = new THREE.LineSegments(geometry, material);
      line.frustumCulled = false;
      scene.add(line);
      lines.push(geometry);
      materials.push(material);
    }
    return function (k) {
      const first = Math.max(0, k - layer.trail);
      const rgbNow = frameColours ? coloursAt(k, null) : null;
      for (let i = 0; i < pointCount; i++) {
        let start = first;
        if (alive) {
          if (!alive[k * pointCount + i]) {
            lines[i].setDrawRange(0, 0);
            continue;
          }
          // Back from k to the frame the point was born in, or to the trail's first frame.
          start = k;
          while (start > first && !(births && births[start * pointCount + i])) start--;
        }
        if (rgbNow) srgb(rgbNow, i, materials[i].color).lerp(background, 0.4);
        const path = lines[i].getAttribute("position");
        const out = path.array;
        for (let f = start, j = 0; f <= k; f++, j += 3) {
          const from = f * stride + 3 * i;
          out[j] = allPositions[from];
          out[j + 1] = allPositions[from + 1];
          out[j + 2] = allPositions[from + 2];
        }
        path.needsUpdate = true;
        lines[i].setDrawRange(0, 2 * (k - start));
      }
    };
  }

  function indexedGeometry(layer, width) {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", current);
    geometry.setIndex(new THREE.BufferAttribute(decode(layer.indices, Uint32Array), 1));
    if (geometry.index.count !== layer.count * width) throw new Error("corrupt index data");
    return geometry;
  }

  const LAYERS = {
    /* Spheres of the recorded radii: one instanced mesh, a matrix per point per frame. When
     * points are born and die, the live ones of a frame fill the first instances (mesh.count),
     * each with its radius and colour in that frame. With faces, only the points on no face
     * (layer.spheres) are spheres: the others are the surface's vertices. */
    points(layer) {
      if (layer.stars) return LAYERS.stars(layer);
      const radius = layer.radius ? decode(layer.radius, Float32Array) : null;
      const onFaces = layer.spheres !== undefined; // "" when every point is on a face
      const sphere = new Uint8Array(pointCount).fill(onFaces ? 0 : 1);
      if (onFaces) for (const i of decode(layer.spheres, Uint32Array)) sphere[i] = 1;
      const sphereCount = sphere.reduce((sum, s) => sum + s, 0);
      // The finest sphere whose triangles, over all spheres, fit the budget.
      let around = SPHERE_SEGMENTS.find((n) => sphereCount * n * n <= SPHERE_TRIANGLE_BUDGET);
      if (around === undefined) around = SPHERE_SEGMENTS[SPHERE_SEGMENTS.length - 1];
      const ball = new THREE.SphereGeometry(1, around, around / 2 + 1);
      const coloured = Boolean(layer.colors || frameColours);
      const material = new THREE.MeshLambertMaterial({
        color: coloured ? 0xffffff : POINT_COLOUR }); // white: instance colours multiply
      const mesh = new THREE.InstancedMesh(ball, material, pointCount);
      const staticRgb = layer.colors ? decode(layer.colors, Uint8Array) : null;
      // Instance n is point n unless points die or are on faces: then the instances drawn
      // are packed, and radii and colours move with their points.
      const packed = Boolean(alive) || onFaces;
      // Colours move with their points between instances when packed, or change per frame.
      const recolour = coloured && Boolean(packed || frameColours);
      if (staticRgb && !recolour) { // per-point sRGB colours of the recording, set once
        for (let i = 0; i < pointCount; i++) mesh.setColorAt(i, srgb(staticRgb, i));
      }
      const trail = layer.trail > 0 ? trailLines(layer) : null;
      mesh.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
      mesh.frustumCulled = false; // the points move; a bounding sphere from frame 0 would lie
      const matrices = mesh.instanceMatrix.array; // column-major 4x4 per point
      for (let i = 0; i < pointCount; i++) {
        matrices.fill(0, 16 * i, 16 * i + 16);
        if (radius) matrices[16 * i] = matrices[16 * i + 5] = matrices[16 * i + 10] = radius[i];
        matrices[16 * i + 15] = 1;
      }
      scene.add(mesh);
      pointMesh = mesh;
      const colour = new THREE.Color();
      return function update() {
        const xyz = current.array;
        const base = frame * pointCount;
        const rgb = recolour ? coloursAt(frame, staticRgb) : null;
        let n = 0; // instances drawn
        for (let i = 0; i < pointCount; i++) {
          if (!sphere[i] || (alive && !alive[base + i])) continue;
          const m = 16 * n;
          if (packed || frameRadii) {
            const r = frameRadii ? frameRadii[base + i] : radius[i];
            matrices[m] = matrices[m + 5] = matrices[m + 10] = r;
          }
          matrices[m + 12] = xyz[3 * i];
          matrices[m + 13] = xyz[3 * i + 1];
          matrices[m + 14] = xyz[3 * i + 2];
          if (rgb) mesh.setColorAt(n, srgb(rgb, i, colour));
          n++;
        }
        mesh.count = n;
        mesh.instanceMatrix.needsUpdate = true;
        if (rgb && mesh.instanceColor) mesh.instanceColor.needsUpdate = true;
        if (trail) trail(frame);
      };
    },
    /* Many points without a size (a galaxy, a star cluster): spots of light added together
     * on a night sky, without a ground, so that density and structure show. */
    stars(layer) {
      starField = true;
      scene.background = new THREE.Color(NIGHT);
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute("position", current);
      const staticRgb = layer.colors ? decode(layer.colors, Uint8Array) : null;
      const colours = new THREE.BufferAttribute(new Float32Array(3 * pointCount), 3);
      const colour = new THREE.Color(STAR_COLOUR);
      for (let i = 0; i < pointCount; i++) {
        if (staticRgb) srgb(staticRgb, i, colour);
        colours.setXYZ(i, colour.r, colour.g, colour.b);
      }
      geometry.setAttribute("color", colours);
      const material = new THREE.PointsMaterial({ size: 2, sizeAttenuation: false,
        vertexColors: true, blending: THREE.AdditiveBlending, transparent: true,
        depthWrite: false, opacity: 0.8 });
      const cloud = new THREE.Points(geometry, material);
      cloud.frustumCulled = false; // the points move
      scene.add(cloud);
      starCloud = cloud;
      return function update() {
        const rgb = frameColours ? coloursAt(frame, staticRgb) : null;
        if (!rgb) return;
        for (let i = 0; i < pointCount; i++) {
          srgb(rgb, i, colour);
          colours.setXYZ(i, colour.r, colour.g, colour.b);
        }
        colours.needsUpdate = true;
      };
    },
    /* Lines between pairs of points (ropes, springs). */
    edges(layer) {
      const lines = new THREE.LineSegments(
        indexedGeometry(layer, 2), new THREE.LineBasicMaterial({ color: EDGE_COLOUR }));
      lines.frustumCulled = false;
      scene.add(lines);
      return function update() {};
    },
    /* Triangles between points (cloth, soft bodies), shaded from both sides. */
    faces(layer) {
      const geometry = indexedGeometry(layer, 3);
      const material = new THREE.MeshLambertMaterial({
        color: FACE_COLOUR, side: THREE.DoubleSide,
        polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1, // edges stay on top
      });
      const mesh = new THREE.Mesh(geometry, material);
      mesh.frustumCulled = false;
      scene.add(mesh);
      return function update() { geometry.computeVertexNormals(); };
    },
    /* Rigid bodies: one mesh per body, its surface in its own axes (normals computed once),
     * moved every frame by its object transform, a position and a quaternion: no vertex of a
     * rigid body changes in its own axes, so none is sent or touched per frame. */
    bodies(layer) {
      const count = layer.count;
      const vertices = decode(layer.vertices, Float32Array);
      const triangles = decode(layer.triangles, Uint32Array);
      const vertexStart = decode(layer.vertex_start, Uint32Array);
      const triangleStart = decode(layer.triangle_start, Uint32Array);
      const rgb = decode(layer.colors, Uint8Array);
      const positions = decode(layer.positions, Float32Array); // (frames, B, 3) [m]
      const orientations = decode(layer.orientations, Float32Array); // (frames, B, 4) w, x, y, z
      if (positions.length !== 3 * frames * count || orientations.length !== 4 * frames * count) {
        throw new Error("corrupt body data");
      }
      for (let b = 0; b < count; b++) {
        const geometry = new THREE.BufferGeometry();
        geometry.setAttribute("position", new THREE.BufferAttribute(
          vertices.slice(3 * vertexStart[b], 3 * vertexStart[b + 1]), 3));
        geometry.setIndex(new THREE.BufferAttribute(
          triangles.slice(3 * triangleStart[b], 3 * triangleStart[b + 1]), 1));
        geometry.computeVertexNormals();
        const material = new THREE.MeshLambertMaterial({ color: srgb(rgb, b) });
        const mesh = new THREE.Mesh(geometry, material);
        mesh.name = layer.names[b];
        scene.add(mesh);
        bodyMeshes.push(mesh);
      }
      return function update() {
        for (let b = 0; b < count; b++) {
          const i = frame * count + b;
          bodyMeshes[b].position.fromArray(positions, 3 * i);
          // three.js orders a quaternion (x, y, z, w); the recording (w, x, y, z).
          bodyMeshes[b].quaternion.set(orientations[4 * i + 1], orientations[4 * i + 2],
            orientations[4 * i + 3], orientations[4 * i]);
        }
      };
    },
    /* The rigid bodies' contacts of each frame, drawn while the "contacts" box is ticked:
     * a small sphere at each point coloured by Baraff's class (colliding red, resting green,
     * separating blue) and a line along its normal. */
    contacts(layer) {
      const count = layer.count;
      const points = decode(layer.points, Float32Array); // (frames, K, 3) [m]
      const normals = decode(layer.normals, Float32Array);
      const classes = decode(layer.classes, Int8Array); // (frames, K), -1: an empty slot
      if (points.length !== 3 * frames * count || classes.length !== frames * count) {
        throw new Error("corrupt contact data");
      }
      const marker = layer.marker;
      const mesh = new THREE.InstancedMesh(
        new THREE.SphereGeometry(marker, 8, 6), new THREE.MeshLambertMaterial(), Math.max(count, 1));
      mesh.frustumCulled = false;
      const linePositions = new Float32Array(6 * Math.max(count, 1));
      const lineGeometry = new THREE.BufferGeometry();
      lineGeometry.setAttribute("position", new THREE.BufferAttribute(linePositions, 3));
      const lines = new THREE.LineSegments(lineGeometry,
        new THREE.LineBasicMaterial({ color: 0x222222 }));
      lines.frustumCulled = false;
      scene.add(mesh);
      scene.add(lines);
      const colours = [new THREE.Color(0xd62728), new THREE.Color(0x2ca02c),
        new THREE.Color(0x1f77b4)];
      const matrices = mesh.instanceMatrix.array; // column-major 4×4 per instance
      for (let i = 0; i < Math.max(count, 1); i++) {
        matrices.fill(0, 16 * i, 16 * i + 16);
        matrices[16 * i] = matrices[16 * i + 5] = matrices[16 * i + 10] = matrices[16 * i + 15] = 1;
      }
      contactView.layer = layer;
      contactView.mesh = mesh;
      contactView.lines = lines;
      return function update() {
        const on = contactToggle.checked;
        mesh.visible = lines.visible = on;
        let n = 0;
        for (let i = 0; i < count; i++) {
          const c = classes[frame * count + i];
          if (c < 0) continue;
          const j = 3 * (frame * count + i);
          matrices[16 * n + 12] = points[j];
          matrices[16 * n + 13] = points[j + 1];
          matrices[16 * n + 14] = points[j + 2];
          mesh.setColorAt(n, colours[c]);
          for (let a = 0; a < 3; a++) {
            linePositions[6 * n + a] = points[j + a];
            linePositions[6 * n + 3 + a] = points[j + a] + 5 * marker * normals[j + a];
          }
          n++;
        }
        mesh.count = n;
        mesh.instanceMatrix.needsUpdate = true;
        if (mesh.instanceColor) mesh.instanceColor.needsUpdate = true;
        lineGeometry.setDrawRange(0, 2 * n);
        lineGeometry.attributes.position.needsUpdate = true;
        contactView.shown = n;
      };
    },
    /* Walls (planes other than floors), cut to the scene's box: translucent, both sides. */
    walls(layer) {
      return LAYERS.scenery(layer, new THREE.MeshLambertMaterial({ transparent: true,
        opacity: 0.25, side: THREE.DoubleSide, depthWrite: false }));
    },
    /* Static colliders: one mesh per collider, in the world frame, drawn as placed. */
    scenery(layer, look = null) {
      const vertices = decode(layer.vertices, Float32Array);
      const triangles = decode(layer.triangles, Uint32Array);
      const vertexStart = decode(layer.vertex_start, Uint32Array);
      const triangleStart = decode(layer.triangle_start, Uint32Array);
      const rgb = decode(layer.colors, Uint8Array);
      if (vertexStart.length !== layer.count + 1 || triangleStart.length !== layer.count + 1) {
        throw new Error("corrupt scenery data");
      }
      for (let c = 0; c < layer.count; c++) {
        const geometry = new THREE.BufferGeometry();
        geometry.setAttribute("position", new THREE.BufferAttribute(
          vertices.slice(3 * vertexStart[c], 3 * vertexStart[c + 1]), 3));
        geometry.setIndex(new THREE.BufferAttribute(
          triangles.slice(3 * triangleStart[c], 3 * triangleStart[c + 1]), 1));
        geometry.computeVertexNormals();
        const material = look ? look.clone() : new THREE.MeshLambertMaterial();
        material.color.copy(srgb(rgb, c));
        const mesh = new THREE.Mesh(geometry, material);
        mesh.name = layer.names[c];
        scene.add(mesh);
        (look ? wallMeshes : sceneryMeshes).push(mesh);
      }
      return function update() {};
    },
  };

  const contactToggle = document.getElementById("contacts");
  const contactView = { layer: null, shown: 0 }; // read back by visviva.contacts()
  let pointMesh = null; // the points layer's instanced mesh, read back by visviva.drawn()
  let starField = false; // the points are drawn as a star field: no ground grid
  let starCloud = null; // its points, read back by visviva.stars()
  const bodyMeshes = []; // the bodies layer's meshes, read back by visviva.bodies()
  const sceneryMeshes = []; // the scenery layer's meshes, read back by visviva.scenery()
  const wallMeshes = []; // the walls layer's meshes, read back by visviva.walls()
  const updates = [];
  for (const [name, layer] of Object.entries(data.layers)) {
    if (!(name in LAYERS)) throw new Error("this viewer cannot draw layer " + name);
    updates.push(LAYERS[name](layer));
  }

  /* Ground grid at y = min(0, lowest point), a whole number of cells wide. */
  const cell = Math.pow(10, Math.floor(Math.log10(size / 4)));
  const cells = 2 * Math.ceil((0.75 * size) / cell);
  const grid = new THREE.GridHelper(cells * cell, cells, 0x8794a3, 0xc3cad3);
  grid.position.set(Math.round(centre.x / cell) * cell, Math.min(0, low.y),
    Math.round(centre.z / cell) * cell);
  if (!starField) scene.add(grid);

  /* Orbit camera: spherical coordinates (distance, polar angle from +Y, azimuth from +Z)
   * around a target point; drag orbits, right- or shift-drag pans, the wheel zooms. */
  // The scene's own first view, if it set a camera or framed one body; else the whole scene.
  const given = data.view;
  const camera = new THREE.PerspectiveCamera(given ? given.fov : FIELD_OF_VIEW, 1, 0.01, 100);
  const home = given ? {
    target: new THREE.Vector3().fromArray(given.target),
    distance: given.distance,
    polar: given.polar,
    azimuth: given.azimuth,
  } : {
    target: centre.clone(),
    distance: (FRAMING_MARGIN * 0.5 * size) / Math.sin((FIELD_OF_VIEW * Math.PI) / 360),
    polar: 1.15,
    azimuth: 0.6,
  };
  const view = { target: home.target.clone(), distance: home.distance, polar: home.polar,
    azimuth: home.azimuth };

  function placeCamera() {
    const s = Math.sin(view.polar);
    camera.position.set(s * Math.sin(view.azimuth), Math.cos(view.polar),
      s * Math.cos(view.azimuth)).multiplyScalar(view.distance).add(view.target);
    camera.near = view.distance / 200;
    camera.far = view.distance + 20 * size;
    camera.updateProjectionMatrix();
    camera.lookAt(view.target);
    camera.updateMatrixWorld();
    needsDraw = true;
  }

  let drag = null;
  canvas.addEventListener("pointerdown", (event) => {
    canvas.setPointerCapture(event.pointerId);
    const pan = event.button === 2 || event.shiftKey;
    drag = { id: event.pointerId, pan, x: event.clientX, y: event.clientY };
  });
  canvas.addEventListener("pointermove", (event) => {
    if (!drag || drag.id !== event.pointerId) return;
    const dx = event.clientX - drag.x;
    const dy = event.clientY - drag.y;
    drag.x = event.clientX;
    drag.y = event.clientY;
    const height = canvas.clientHeight || 1;
    if (drag.pan) {
      // One pixel moves the target by the size of a pixel at the target's depth.
      const perPixel = (2 * view.distance * Math.tan((FIELD_OF_VIEW * Math.PI) / 360)) / height;
      const right = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 0);
      const up = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 1);
      view.target.addScaledVector(right, -dx * perPixel).addScaledVector(up, dy * perPixel);
    } else {
      view.azimuth -= (ORBIT_RATE * dx) / height;
      view.polar = Math.min(Math.PI - POLAR_LIMIT,
        Math.max(POLAR_LIMIT, view.polar - (ORBIT_RATE * dy) / height));
    }
    placeCamera();
  });
  const endDrag = () => { drag = null; };
  canvas.addEventListener("pointerup", endDrag);
  canvas.addEventListener("pointercancel", endDrag);
  canvas.addEventListener("contextmenu", (event) => event.preventDefault());
  canvas.addEventListener("wheel", (event) => {
    event.preventDefault();
    view.distance = Math.min(100 * size,
      Math.max(1e-3 * size, view.distance * Math.exp(event.deltaY * ZOOM_RATE)));
    placeCamera();
  }, { passive: false });
  canvas.addEventListener("dblclick", () => {
    Object.assign(view, home, { target: home.target.clone() });
    placeCamera();
  });

  /* Playback and controls. */
  const playButton = document.getElementById("play");
  const slider = document.getElementById("slider");
  const timeText = document.getElementById("time");
  const speedSelect = document.getElementById("speed");
  slider.max = String(frames - 1);
  document.getElementById("title").textContent = data.title;
  document.title = data.title;
  const legendRows = document.getElementById("legend-rows");
  for (const [label, value] of data.legend) {
    const row = legendRows.insertRow();
    row.insertCell().textContent = label;
    row.insertCell().textContent = value;
  }

  let frame = -1;
  let playing = false;
  let speed = 1;
  let anchorTime = 0; // performance.now() [ms] when frame anchorFrame was shown
  let anchorFrame = 0;
  let needsDraw = true;

  function show(k) {
    if (k === frame) return;
    frame = k;
    loadFrame(k);
    for (const update of updates) update();
    if (data.follow) { // the camera's target moves with the followed body's centre
      const body = bodyMeshes[data.follow.body];
      view.target.fromArray(data.follow.centre).applyQuaternion(body.quaternion)
        .add(body.position);
      placeCamera();
    }
    slider.value = String(k);
    const [unit, seconds, decimals] = data.time_unit;
    timeText.textContent = "t = " + (times[k] / seconds).toFixed(decimals) + " " + unit +
      (data.to_scale ? "" : ", sizes not to scale") + "  (" + (k + 1) + "/" + frames + ")";
    needsDraw = true;
  }

  /* The bodies' names over them (data.labels), placed where each body's centre is drawn. */
  const nameTags = data.labels ? bodyMeshes.map((mesh) => {
    const tag = document.createElement("div");
    tag.className = "name-tag";
    tag.textContent = mesh.name;
    tag.style.cssText = "position:fixed;pointer-events:none;transform:translate(-50%,-150%);" +
      "font:13px sans-serif;color:#fff;background:rgba(25,30,38,0.6);padding:1px 5px;" +
      "border-radius:3px;white-space:nowrap";
    document.body.appendChild(tag);
    return tag;
  }) : [];

  function placeNameTags() {
    const rect = canvas.getBoundingClientRect();
    const where = new THREE.Vector3();
    nameTags.forEach((tag, b) => {
      where.copy(bodyMeshes[b].position).project(camera);
      tag.hidden = where.z > 1;
      tag.style.left = rect.left + (0.5 + 0.5 * where.x) * rect.width + "px";
      tag.style.top = rect.top + (0.5 - 0.5 * where.y) * rect.height + "px";
    });
  }

  function draw() {
    renderer.render(scene, camera);
    placeNameTags();
    needsDraw = false;
  }

  function anchor() {
    anchorTime = performance.now();
    anchorFrame = frame;
  }

  function setPlaying(on) {
    playing = on;
    if (on) anchor();
    playButton.textContent = on ? "Pause" : "Play";
  }

  function setFrame(k) {
    if (!Number.isInteger(k) || k < 0 || k >= frames) {
      throw new RangeError("frame must be a whole number in 0.." + (frames - 1) + " (got " + k + ")");
    }
    show(k);
    if (playing) anchor();
    draw();
  }

  playButton.addEventListener("click", () => setPlaying(!playing));
  slider.addEventListener("input", () => setFrame(Number(slider.value)));
  contactToggle.parentElement.hidden = !("contacts" in data.layers);
  contactToggle.addEventListener("change", () => {
    for (const update of updates) update();
    needsDraw = true;
  });
  speedSelect.addEventListener("change", () => {
    speed = Number(speedSelect.value);
    if (playing) anchor();
  });
  window.addEventListener("keydown", (event) => {
    const target = event.target;
    // Focused controls keep their own keys (space presses a focused button, arrows move the slider).
    if (target === playButton || target === slider || target === speedSelect) return;
    if (event.code === "Space") {
      event.preventDefault();
      setPlaying(!playing);
    } else if (event.code === "ArrowRight" || event.code === "ArrowLeft") {
      setPlaying(false);
      setFrame((frame + (event.code === "ArrowRight" ? 1 : frames - 1)) % frames);
    }
  });

  function resize() {
    const width = canvas.clientWidth || 1;
    const height = canvas.clientHeight || 1;
    renderer.setSize(width, height, false);
    camera.aspect = width / height;
    placeCamera();
  }
  window.addEventListener("resize", resize);

  function tick(now) {
    if (playing && frames > 1) {
      const elapsed = Math.max(0, now - anchorTime) / 1000; // [s]
      show((anchorFrame + Math.floor(elapsed * fps * speed)) % frames);
    }
    if (needsDraw) draw();
    requestAnimationFrame(tick);
  }

  window.visviva = {
    frames,
    fps,
    times: Array.from(times),
    setFrame,
    frame: () => frame,
    play: () => setPlaying(true),
    pause: () => setPlaying(false),
    playing: () => playing,
    /* Positions [m] of output frame k as a flat array (P * 3), as decoded (float32). */
    points: (k) => Array.from(allPositions.subarray(k * stride, (k + 1) * stride)),
    /* The spheres drawn in the frame shown: centres [m], radii [m] and 8-bit sRGB colours
     * (null for the default colour), read back from the instanced mesh. */
    drawn: () => {
      if (!pointMesh) return { count: 0, centres: [], radii: [], colours: null };
      const m = pointMesh.instanceMatrix.array;
      const c = pointMesh.instanceColor;
      const out = { count: pointMesh.count, centres: [], radii: [], colours: c ? [] : null };
      for (let j = 0; j < pointMesh.count; j++) {
        out.centres.push([m[16 * j + 12], m[16 * j + 13], m[16 * j + 14]]);
        out.radii.push(m[16 * j]);
        if (c) {
          const hex = new THREE.Color().fromArray(c.array, 3 * j).getHex();
          out.colours.push([hex >> 16, (hex >> 8) & 255, hex & 255]);
        }
      }
      return out;
    },
    /* The rigid bodies as drawn in the frame shown: each mesh's name, position [m] and
     * orientation (w, x, y, z), read back from its object transform. */
    bodies: () => bodyMeshes.map((mesh) => ({
      name: mesh.name,
      position: mesh.position.toArray(),
      orientation: [mesh.quaternion.w, mesh.quaternion.x, mesh.quaternion.y, mesh.quaternion.z],
    })),
    /* The contacts as drawn in the frame shown: whether the box is ticked and how many. */
    contacts: () => ({
      recorded: contactView.layer !== null,
      visible: contactView.layer !== null && contactToggle.checked,
      shown: contactView.shown,
    }),
    /* The star field as drawn, or null: its number of points and whether light adds up. */
    stars: () => starCloud && ({ count: starCloud.geometry.attributes.position.count,
      additive: starCloud.material.blending === THREE.AdditiveBlending }),
    /* The bodies' name tags as shown: their texts. */
    nameTags: () => nameTags.map((tag) => tag.textContent),
    /* The walls as drawn: each mesh's name and opacity. */
    walls: () => wallMeshes.map((mesh) => ({ name: mesh.name, opacity: mesh.material.opacity })),
    /* The orbit camera: its target [m] and distance [m] from it. */
    view: () => ({ target: view.target.toArray(), distance: view.distance }),
    /* The static colliders as drawn: each mesh's name and number of triangles. */
    scenery: () => sceneryMeshes.map((mesh) => ({
      name: mesh.name,
      triangles: mesh.geometry.index.count / 3,
    })),
    ready: false,
    readyTime: null, // performance.now() [ms since navigation start] at the first draw
  };

  /* Ready once the first frame is drawn: a GPU fence, polled between tasks (its status only
   * changes when control returns to the event loop), tells when the GPU, or SwiftShader,
   * has finished it. gl.finish() does not wait in Chrome; reading pixels back would stall. */
  function whenDrawn(callback) {
    const gl = renderer.getContext();
    const fence = gl.fenceSync(gl.SYNC_GPU_COMMANDS_COMPLETE, 0);
    gl.flush();
    (function poll() {
      if (gl.clientWaitSync(fence, 0, 0) === gl.TIMEOUT_EXPIRED) {
        setTimeout(poll, 2);
        return;
      }
      gl.deleteSync(fence);
      callback();
    })();
  }

  resize();
  show(0);
  draw();
  whenDrawn(() => {
    window.visviva.readyTime = performance.now();
    window.visviva.ready = true;
    setPlaying(frames > 1); // an animation plays as soon as it is shown
    requestAnimationFrame(tick);
  });
})();
