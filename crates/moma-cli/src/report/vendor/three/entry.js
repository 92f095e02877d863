// The parts of three.js the mission report's 3-D view uses (bundled as the global THREE).
export {
  WebGLRenderer, Scene, PerspectiveCamera, AmbientLight, DirectionalLight, HemisphereLight,
  Mesh, Group, Line, MeshLambertMaterial, MeshBasicMaterial, LineBasicMaterial,
  BoxGeometry, CylinderGeometry, SphereGeometry, CapsuleGeometry, PlaneGeometry,
  BufferGeometry, BufferAttribute, Float32BufferAttribute, Matrix4, Quaternion, Vector3,
  Color, Texture, NearestFilter, SRGBColorSpace, DoubleSide
} from 'three';
