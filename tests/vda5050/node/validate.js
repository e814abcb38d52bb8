// Validates VDA 5050 2.0 documents with vda-5050-lib's validators, compiled from the 2.0 JSON Schemas.
//
// A long-lived process for tests/vda5050/official.py: it reads one JSON object per line on stdin,
// {"topic": "order" | "instantActions" | "state" | "visualization" | "connection" | "factsheet",
//  "document": {...}}, and answers each with one JSON line, {"errors": [...]}: empty when the document is
// valid, else the validator's findings as "instanceLocation: keywordLocation" strings (the compiled
// validators stop at their first finding). A request it cannot serve is answered {"fatal": "..."}.
"use strict";

const path = require("path");
const readline = require("readline");

const validators = require(path.join(__dirname, "node_modules", "vda-5050-lib", "common", "vda-5050-validators-2.0.js"));

const byTopic = {
    connection: validators.validateConnection,
    factsheet: validators.validateFactsheet,
    instantActions: validators.validateInstantActions,
    order: validators.validateOrder,
    state: validators.validateState,
    visualization: validators.validateVisualization,
};

function answer(line) {
    let request;
    try {
        request = JSON.parse(line);
    } catch (error) {
        return { fatal: `request is not JSON: ${error.message}` };
    }
    const validate = byTopic[request.topic];
    if (validate === undefined) {
        return { fatal: `topic ${JSON.stringify(request.topic)} is not one of ${Object.keys(byTopic).join(", ")}` };
    }
    if (validate(request.document)) {
        return { errors: [] };
    }
    return { errors: (validate.errors || []).map((e) => `${e.instanceLocation}: ${e.keywordLocation}`) };
}

const lines = readline.createInterface({ input: process.stdin, terminal: false });
lines.on("line", (line) => {
    if (line.trim() !== "") {
        process.stdout.write(JSON.stringify(answer(line)) + "\n");
    }
});
