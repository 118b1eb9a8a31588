// skysh {{VERSION}}: TypeScript declarations of the ES module written by
// `skysh export --format js{{COMMAND_OPTIONS}}` (the .mjs beside this file, whose header documents every option).

/** Engine names the engine option takes. */
export type Engine = {{ENGINE_UNION}};

export interface CoefficientOptions {
  /** SH bands, an integer in [1, {{MAX_BANDS}}]; default {{DEFAULT_BANDS}}. */
  bands?: number;
  /** Zonal sinc filter (Habel eq. 5); default !irradiance, false with an engine or the irradiance table. */
  gibbs?: boolean;
  /** Irradiance instead of radiance (clamped-cosine convolution); default false; must be false with an engine. */
  irradiance?: boolean;
  /** Window so the irradiance is never negative (the least window, any band count); default irradiance (or an engine). */
  dering?: boolean;
  /**
   * The certified 3-band irradiance table (never negative) instead of the filtered, deringed sky: null (default) by
   * intent, for irradiance or an engine at 3 bands unless gibbs is true or dering false; false never; true always.
   */
  irradianceTable?: boolean | null;
  /** Add the sun's disk (a windowed delta, colour clamped at 0); default false. */
  sun?: boolean;
  /** A Lambertian ground below the horizon: a number or [r, g, b] in [0, 1]; default 0 (black). */
  groundAlbedo?: number | readonly [number, number, number] | Float64Array;
  /** Return this engine's numbers (its flat layout, see engineLayout) instead of skysh's. */
  engine?: Engine | null;
  /** Fill and return this array (its length must be the result's) instead of a new one. */
  out?: number[] | Float64Array;
}

/** The sun as a directional light. */
export interface SunLight {
  /** Unit vector towards the sun (Z up). */
  readonly direction: [number, number, number];
  /** Direct normal illuminance, lux per channel (linear sRGB). */
  readonly rgb: [number, number, number];
}

export interface EngineLayout {
  /** The engine's array shape (row-major); the product is the result's length. */
  readonly shape: readonly number[];
  /** The labels of the rows (first axis) of shape, in the engine's vocabulary. */
  readonly labels: readonly string[];
}

export declare const SKYSH_VERSION: string;
export declare const MAX_BANDS: number;
export declare const ENGINES: readonly Engine[];
export declare const SUN_ZENITH_DOMAIN: readonly [number, number];
export declare const TURBIDITY_DOMAIN: readonly [number, number];

/**
 * The sky's SH coefficients for one frame: bands * bands * 3 numbers, coefficient-major RGB
 * (or the engine's values). Radians; turbidity in {{TURBIDITY_DOMAIN}}. Throws RangeError / TypeError.
 */
export declare function coefficients<T extends number[] | Float64Array>(
  sunZenith: number, turbidity: number, sunAzimuth: number | undefined, options: CoefficientOptions & { out: T },
): T;
export declare function coefficients(
  sunZenith: number, turbidity: number, sunAzimuth?: number, options?: CoefficientOptions,
): number[];

/** The sun as a directional light (skysh.SkySH.sun_light). Throws RangeError / TypeError. */
export declare function sunLight(sunZenith: number, turbidity: number, sunAzimuth?: number): SunLight;

/** The engine's layout for a band count (default {{DEFAULT_BANDS}}). */
export declare function engineLayout(engine: Engine, bands?: number): EngineLayout;
