// skysh {{VERSION}}: TypeScript declarations of the ES module written by
// skysh.export.hosek.export_source("js", bands={{MAX_BANDS}}, accuracy="{{ACCURACY}}") (hosek_wilkie.mjs, beside
// this file, whose header documents the API).

/** A ground albedo: one number for every channel or [r, g, b], each in [0, 1]. */
export type Albedo = number | readonly [number, number, number] | Float64Array;

export interface CoefficientOptions {
  /** Irradiance instead of radiance (clamped-cosine convolution); default false. */
  irradiance?: boolean;
  /** Zonal sinc filter (Habel eq. 5); default !irradiance. */
  gibbs?: boolean;
  /** Window so the irradiance is never negative (the least window); default irradiance. */
  dering?: boolean;
  /** The ground albedo (each channel's parameters linear in its own albedo); default 0. */
  albedo?: Albedo;
  /** Fill and return this array (its length must be 3 bands^2) instead of a new one. */
  out?: number[] | Float64Array;
}

/** A sky built once by createSky: its rule and scratch for `bands` bands. */
export interface Sky {
  /** The band count of the results. */
  readonly bands: number;
  /** Whether the last call's deringing found no non-negative window (its last row applied). */
  readonly deringFailed: boolean;
  /** bands * bands * 3 numbers, coefficient-major linear sRGB, cd/m^2 (irradiance: x sr). Radians. */
  coefficients<T extends number[] | Float64Array>(
    sunZenith: number, turbidity: number, sunAzimuth: number | undefined, options: CoefficientOptions & { out: T },
  ): T;
  coefficients(sunZenith: number, turbidity: number, sunAzimuth?: number, options?: CoefficientOptions): number[];
}

/** The model's parameters per channel [r, g, b] (Hosek and Wilkie 2012, eq. 9); LM in the dataset's units. */
export interface Configuration {
  readonly A: [number, number, number];
  readonly B: [number, number, number];
  readonly C: [number, number, number];
  readonly D: [number, number, number];
  readonly E: [number, number, number];
  readonly F: [number, number, number];
  readonly G: [number, number, number];
  readonly H: [number, number, number];
  readonly I: [number, number, number];
  readonly LM: [number, number, number];
  /** 683 lm/W: LM times this is cd/m^2. */
  readonly efficacy: number;
}

export declare const SKYSH_VERSION: string;
/** The most bands createSky takes ({{MAX_BANDS}}). */
export declare const MAX_BANDS: number;
export declare const ACCURACY: string;
export declare const LUMINOUS_EFFICACY: number;
export declare const SUN_ZENITH_DOMAIN: readonly [number, number];
export declare const TURBIDITY_DOMAIN: readonly [number, number];
export declare const ALBEDO_DOMAIN: readonly [number, number];

/** Build the rule once for `bands` bands (default MAX_BANDS). Throws RangeError / TypeError. */
export declare function createSky(bands?: number): Sky;
/** The model's parameters at a sun position. Throws RangeError / TypeError. */
export declare function configuration(sunZenith: number, turbidity: number, albedo?: Albedo): Configuration;
/** The sky's linear sRGB radiance, cd/m^2, in a unit direction (Z up); 0 below the horizon. */
export declare function radiance(
  direction: readonly [number, number, number] | Float64Array, sunZenith: number, turbidity: number,
  sunAzimuth?: number, albedo?: Albedo,
): [number, number, number];
