// lodkit's three.js integration: streamed `.pop` meshes and view-dependent
// `.mco` models, decoded by lodkit's own Rust code compiled to wasm.
export { PopLoader, geometryFromMesh } from './PopLoader.js';
export { McoModel } from './McoModel.js';
export { McoLoader } from './McoLoader.js';
export { wasmModule, DEFAULT_WASM_URL } from './wasm.js';
