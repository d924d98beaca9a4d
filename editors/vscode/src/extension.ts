// The MCL extension: starts the MCL language server (`mcl lsp`, over standard
// input and output) for `.mcl` files. Highlighting, snippets, comments,
// brackets and folding are declarative (package.json, syntaxes/, snippets/,
// language-configuration.json).

import * as vscode from 'vscode';
import {
  LanguageClient,
  LanguageClientOptions,
  ServerOptions,
  State,
  TransportKind,
} from 'vscode-languageclient/node';

let client: LanguageClient | undefined;
let output: vscode.OutputChannel | undefined;

export async function activate(context: vscode.ExtensionContext): Promise<void> {
  output = vscode.window.createOutputChannel('MCL Language Server');
  context.subscriptions.push(
    output,
    vscode.commands.registerCommand('mcl.restartServer', () => restart()),
    vscode.commands.registerCommand('mcl.showServerOutput', () => output?.show(true)),
    vscode.workspace.onDidChangeConfiguration((e) => {
      if (e.affectsConfiguration('mcl.server') || e.affectsConfiguration('mcl.ros2Bridge')) {
        void restart();
      }
    }),
  );
  await start();
}

export async function deactivate(): Promise<void> {
  await stop();
}

/** The command that starts the server, from the `mcl.server.*` settings. */
export function serverCommand(config: vscode.WorkspaceConfiguration): { command: string; args: string[] } {
  const command = (config.get<string>('server.path') || 'mcl').trim() || 'mcl';
  const args = config.get<string[]>('server.args') ?? ['lsp'];
  return { command, args };
}

async function start(): Promise<void> {
  const config = vscode.workspace.getConfiguration('mcl');
  if (!config.get<boolean>('server.enable', true)) {
    output?.appendLine('The MCL language server is disabled (mcl.server.enable).');
    return;
  }
  const { command, args } = serverCommand(config);
  const executable = { command, args, transport: TransportKind.stdio, options: { env: process.env } };
  const serverOptions: ServerOptions = { run: executable, debug: executable };
  const clientOptions: LanguageClientOptions = {
    documentSelector: [
      { scheme: 'file', language: 'mcl' },
      { scheme: 'untitled', language: 'mcl' },
    ],
    outputChannel: output,
    synchronize: {
      // Imported files that change on disk are re-read by the server, and
      // so is the ROS 2 bridge file (mcl.ros2Bridge) when it is saved.
      fileEvents: [
        vscode.workspace.createFileSystemWatcher('**/*.mcl'),
        vscode.workspace.createFileSystemWatcher('**/*.toml'),
      ],
    },
    // The ROS 2 bridge file checked against the open vehicle (docs/ros2.md).
    initializationOptions: { ros2Bridge: config.get<string>('ros2Bridge') || undefined },
  };
  client = new LanguageClient('mcl', 'MCL Language Server', serverOptions, clientOptions);
  try {
    await client.start();
  } catch (err) {
    const message = err instanceof Error ? err.message : String(err);
    output?.appendLine(`Could not start \`${command} ${args.join(' ')}\`: ${message}`);
    const choice = await vscode.window.showErrorMessage(
      `The MCL language server could not be started with \`${command} ${args.join(' ')}\`. ` +
        'Install mcl (`cargo install --path .` in the MCL repository) or set `mcl.server.path`.',
      'Open Settings',
      'Show Output',
    );
    if (choice === 'Open Settings') {
      void vscode.commands.executeCommand('workbench.action.openSettings', 'mcl.server');
    } else if (choice === 'Show Output') {
      output?.show(true);
    }
    client = undefined;
  }
}

async function stop(): Promise<void> {
  const c = client;
  client = undefined;
  if (c && c.state !== State.Stopped) {
    await c.stop();
  }
}

async function restart(): Promise<void> {
  await stop();
  await start();
}
