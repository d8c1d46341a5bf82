export {
  WebGLRenderer, Scene, PerspectiveCamera, Color, BufferGeometry, BufferAttribute, Float32BufferAttribute,
  Mesh, MeshLambertMaterial, MeshBasicMaterial, LineSegments, LineBasicMaterial, Points, PointsMaterial,
  DirectionalLight, AmbientLight, HemisphereLight, DoubleSide, Box3, Vector3, GridHelper, AxesHelper,
} from 'three';
export { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
